#pragma once

#include <memory>

#include "auv/config/option_table.h"
#include "auv/interfaces/component.h"

namespace auv::demo {

/// Publishes a numbered greeting on `chatter` and a circular trajectory on `nav/odometry`;
/// answers `<node>/reset` (Trigger) by restarting the count.
class Talker : public interfaces::Component {
 public:
  struct Options {
    double rate_hz = 2.0;        ///< Hz, publishing rate
    std::string text = "hello";  ///< Greeting put before the count.
    double circle_radius = 5.0;  ///< m, radius of the published trajectory
    double speed = 0.5;          ///< m/s, speed along the trajectory
    /// The fields with meaning, unit and range: the parameters come from it.
    static const config::OptionTable<Options>& table();
  };

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;
  uint64_t count() const { return count_; }

 private:
  void tick();

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::shared_ptr<interfaces::Publisher<msg::String>> chatter_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_;
  std::shared_ptr<interfaces::Service<msg::TriggerRequest, msg::TriggerReply>> reset_;
  std::shared_ptr<interfaces::Timer> timer_;
  uint64_t count_ = 0;
};

/// Listens on `chatter`, logs what it hears and keeps a latched MissionStatus on
/// `demo/status` (transient local: late joiners see the latest count).
class Listener : public interfaces::Component {
 public:
  struct Options {
    uint64_t log_every = 1;  ///< log one message in this many
    /// The fields with meaning, unit and range: the parameters come from it.
    static const config::OptionTable<Options>& table();
  };

  void configure(interfaces::Node& node) override;
  void cleanup() override;
  uint64_t heard() const { return heard_; }

 private:
  interfaces::Node* node_ = nullptr;
  std::shared_ptr<interfaces::Subscription<msg::String>> chatter_;
  std::shared_ptr<interfaces::Publisher<msg::MissionStatus>> status_;
  uint64_t heard_ = 0;
  Options options_;
};

}  // namespace auv::demo
