#pragma once
// The `foxglove_bridge` component (`auv run foxglove_bridge`): a Foxglove WebSocket protocol v1
// server (README.md) that forwards every DDS topic of the domain unchanged (TopicForwarder)
// and publishes the map, the planner's tree and path, the vehicle and its trajectories, /tf
// and camera frames in Foxglove's own schemas. Services (mission/start, mission/abort) and
// parameters are offered only when their parameters say so: a WebSocket client bypasses DDS
// Security.

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/config/option_table.h"
#include "auv/foxglove_bridge/bridge_core.h"
#include "auv/foxglove_bridge/components/topic_forwarder.h"
#include "auv/foxglove_bridge/scene.h"
#include "auv/foxglove_bridge/websocket_server.h"
#include "auv/interfaces/component.h"
#include "auv/mapping/map_replica.h"

namespace auv::foxglove_bridge {

class FoxgloveBridgeComponent : public interfaces::Component, private Listener {
 public:
  struct Options {
    std::string address = "127.0.0.1";
    int64_t port = 8765;
    int64_t send_buffer_limit = 10000000;
    std::string token;
    std::string token_file;
    bool services = false;
    bool parameters = false;
    double service_timeout = 10.0;
    std::vector<std::string> topics;
    std::vector<std::string> exclude;
    double discovery_period = 0.5;
    std::string odometry_topic = "nav/odometry";
    std::string ground_truth_topic = "sim/ground_truth";
    std::string map_topic = "map/update";
    std::string map_id = "octomap";
    std::string tree_topic = "planner/tree";
    std::string path_topic = "planner/path";
    double map_period = 1.0;
    double tree_period = 1.0;
    bool map_show_free = false;
    bool map_show_unknown = false;
    int64_t map_max_cubes = 200000;
    double vehicle_period = 0.2;
    double trajectory_min_step = 0.25;
    int64_t trajectory_max_points = 20000;
    double vehicle_length = 1.6;
    double vehicle_width = 0.5;
    static const config::OptionTable<Options>& table();
    /// Throws std::invalid_argument naming the parameter.
    void check() const;
  };

  ~FoxgloveBridgeComponent() override;
  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// The port listened on (tests set port 0).
  uint16_t port() const { return server_ ? server_->port() : 0; }
  const WebSocketServer& server() const { return *server_; }
  const BridgeCore& core() const { return *core_; }
  const TopicForwarder& forwarder() const { return *forwarder_; }

 private:
  // Listener
  void channelSubscribed(uint32_t channel) override;
  void channelUnsubscribed(uint32_t channel) override;
  void callService(ClientId client, const ServiceCallRequest& request) override;
  nlohmann::json getParameters(const std::vector<std::string>& names) override;
  void setParameters(const SetParameters& request) override;

  void createVisuals();
  void publishJson(uint32_t channel, const nlohmann::json& message, int64_t stamp_ns);
  void publishMap(bool force);
  void publishVehicle();
  void serviceLoop();
  std::string runService(const ServiceCallRequest& request);

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::unique_ptr<WebSocketServer> server_;
  std::unique_ptr<BridgeCore> core_;
  std::unique_ptr<TopicForwarder> forwarder_;

  // Visual channels (ids in the core) and what they are drawn from: executor thread only,
  // except the `resend_*` flags a new subscriber sets.
  uint32_t map_channel_ = 0, planner_channel_ = 0, vehicle_channel_ = 0, tf_channel_ = 0;
  std::unique_ptr<mapping::MapReplica> map_;
  bool map_dirty_ = false;
  bool tree_dirty_ = false;
  std::atomic<bool> resend_map_{false}, resend_planner_{false};
  std::unique_ptr<Trajectory> estimated_, truth_;
  int64_t last_odometry_ns_ = 0;
  std::shared_ptr<msg::PlannerTree> last_tree_;
  std::shared_ptr<msg::Path> last_path_;
  std::vector<std::shared_ptr<void>> subscriptions_;
  std::shared_ptr<interfaces::Timer> map_timer_, vehicle_timer_, tree_timer_;

  // Services: calls queue for a worker thread (a call waits for its reply; the WebSocket
  // thread must not).
  std::shared_ptr<interfaces::Client<msg::StartMissionRequest, msg::StartMissionReply>> start_;
  std::shared_ptr<interfaces::Client<msg::TriggerRequest, msg::TriggerReply>> abort_;
  std::mutex calls_mutex_;
  std::condition_variable calls_wake_;
  std::deque<std::pair<ClientId, ServiceCallRequest>> calls_;
  bool calls_stop_ = false;
  std::thread service_thread_;
};

/// YAML (a message's to_yaml) as JSON: maps, sequences; scalars that read as JSON numbers or
/// booleans become those, others strings.
nlohmann::json yamlToJson(const YAML::Node& node);
/// Sets the fields of `json` over `defaults` (a message's to_yaml): a request may name only
/// the fields it sets. Throws std::invalid_argument naming a field that is not in `defaults`.
YAML::Node overlayJson(const YAML::Node& defaults, const nlohmann::json& json,
                       const std::string& path = "");

}  // namespace auv::foxglove_bridge
