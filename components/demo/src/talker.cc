#include "talker.h"

#include <cmath>

#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"

namespace auv::demo {

const config::OptionTable<Talker::Options>& Talker::Options::table() {
  using config::Range;
  static const config::OptionTable<Options> kTable = {
      {"rate_hz", &Options::rate_hz, "publishing rate", "Hz", Range::closed(1e-3, 1000.0)},
      {"text", &Options::text, "greeting text"},
      {"circle_radius", &Options::circle_radius, "radius of the trajectory", "m",
       Range::closed(0.1, 1000.0)},
      {"speed", &Options::speed, "speed along the trajectory", "m/s", Range::closed(0.01, 5.0)},
  };
  return kTable;
}

void Talker::configure(interfaces::Node& node) {
  node_ = &node;
  interfaces::declareOptions(node.parameters(), "", Options::table(), options_, false);
  chatter_ = node.createPublisher<msg::String>("chatter", interfaces::commandQos());
  odometry_ = node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  reset_ = node.createService<msg::TriggerRequest, msg::TriggerReply>(
      node.name() + "/reset", [this](const msg::TriggerRequest&, msg::TriggerReply& reply) {
        reply.message("count was " + std::to_string(count_));
        count_ = 0;
      });
}

void Talker::activate() {
  timer_ = node_->createTimer(1.0 / options_.rate_hz, [this] { tick(); });
  AUV_INFO(node_->logger(),
           "talking at " << options_.rate_hz << " Hz on " << interfaces::toString(node_->vendor()));
}

void Talker::deactivate() {
  if (timer_) timer_->cancel();
  timer_.reset();
}

void Talker::cleanup() {
  chatter_.reset();
  odometry_.reset();
  reset_.reset();
}

void Talker::tick() {
  ++count_;
  msg::String text;
  text.data(options_.text + " #" + std::to_string(count_) + " from " + node_->name() + " (" +
            interfaces::toString(node_->vendor()) + ")");
  chatter_->publish(text);

  // A circle in the horizontal plane at 3 m depth (NED: z down), heading along the track.
  const double t = static_cast<double>(count_) / options_.rate_hz;
  const double w = options_.speed / options_.circle_radius;
  msg::Odometry odom;
  odom.header().stamp(interfaces::toMsgTime(node_->clock().nowNs()));
  odom.header().frame_id("world");
  odom.child_frame_id("base_link");
  auto& pose = odom.pose().pose();
  pose.position().x(options_.circle_radius * std::cos(w * t));
  pose.position().y(options_.circle_radius * std::sin(w * t));
  pose.position().z(3.0);
  const double yaw = w * t + M_PI / 2;
  pose.orientation().w(std::cos(yaw / 2));
  pose.orientation().z(std::sin(yaw / 2));
  odom.twist().twist().linear().x(options_.speed);
  odom.twist().twist().angular().z(w);
  odometry_->publish(odom);
}

const config::OptionTable<Listener::Options>& Listener::Options::table() {
  static const config::OptionTable<Options> kTable = {
      {"log_every", &Options::log_every, "log one message in N", "", config::Range::closed(1, 1e9)},
  };
  return kTable;
}

void Listener::configure(interfaces::Node& node) {
  node_ = &node;
  interfaces::declareOptions(node.parameters(), "", Options::table(), options_, false);
  status_ = node.createPublisher<msg::MissionStatus>("demo/status", interfaces::latchedStateQos());
  chatter_ = node.createSubscription<msg::String>(
      "chatter", interfaces::commandQos(),
      std::function<void(const msg::String&)>([this](const msg::String& m) {
        ++heard_;
        if (heard_ % options_.log_every == 0) AUV_INFO(node_->logger(), "heard: " << m.data());
        msg::MissionStatus status;
        status.mission_id(node_->name());
        status.message("heard " + std::to_string(heard_) + " messages, last: " + m.data());
        status_->publish(status);
      }));
}

void Listener::cleanup() {
  chatter_.reset();
  status_.reset();
}

}  // namespace auv::demo

AUV_REGISTER_COMPONENT(auv::demo::Talker, "demo_talker",
                       "publishes a greeting on /chatter and a circle on /nav/odometry")
AUV_REGISTER_COMPONENT(auv::demo::Listener, "demo_listener",
                       "logs /chatter and keeps a latched count on /demo/status")
