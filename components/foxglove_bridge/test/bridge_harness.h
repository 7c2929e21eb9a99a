#pragma once
// A foxglove_bridge component on its own node and executor thread, listening on a free
// loopback port, for the component tests and the benchmark.
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "auv/foxglove_bridge/components/foxglove_bridge_component.h"
#include "auv/interfaces/executor.h"

namespace auv::foxglove_bridge::test {

class BridgeHarness {
 public:
  BridgeHarness(interfaces::Vendor vendor, int domain, std::vector<std::string> overrides = {}) {
    overrides.push_back("port:=0");
    overrides.push_back("discovery_period:=0.1");
    node_ = std::make_unique<interfaces::Node>("foxglove_bridge",
                                               interfaces::nodeOptions(vendor, domain, overrides));
    component_.configure(*node_);
    component_.activate();
    executor_.add(*node_);
    thread_ = std::thread([this] { executor_.spin(); });
  }
  ~BridgeHarness() {
    executor_.shutdown();
    thread_.join();
    component_.deactivate();
    executor_.remove(*node_);
    component_.cleanup();
  }
  std::string uri(const std::string& query = "") const {
    return "ws://127.0.0.1:" + std::to_string(component_.port()) + "/" + query;
  }
  FoxgloveBridgeComponent& component() { return component_; }
  interfaces::Node& node() { return *node_; }

 private:
  std::unique_ptr<interfaces::Node> node_;
  FoxgloveBridgeComponent component_;
  interfaces::Executor executor_;
  std::thread thread_;
};

}  // namespace auv::foxglove_bridge::test
