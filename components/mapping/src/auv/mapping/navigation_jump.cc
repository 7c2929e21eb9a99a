#include "auv/mapping/navigation_jump.h"

#include <stdexcept>

namespace auv::mapping {

const config::OptionTable<NavigationJumpDetector::Options>&
NavigationJumpDetector::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"jump_threshold", &O::jump_threshold_m,
       "a navigation step this much longer than the motion explains is a jump: the map moves "
       "with it (0: never)",
       "m", Range::closed(0.0, 1000.0)},
      {"max_speed", &O::max_speed_mps,
       "the vehicle's top speed: bounds real motion between two navigation samples", "m/s",
       Range::closed(0.1, 50.0)},
      {"jump_log_odds_scale", &O::log_odds_scale,
       "the map moved with a jump takes this times its log-odds", "", Range::aboveUpTo(0.0, 1.0)},
  };
  return kTable;
}

void NavigationJumpDetector::Options::check() const {
  config::checkOptions(*this, table(), "navigation_");
}

NavigationJumpDetector::NavigationJumpDetector(const Options& options) : options_(options) {
  options_.check();
}

std::optional<Eigen::Vector3d> NavigationJumpDetector::add(int64_t stamp_ns,
                                                           const Eigen::Vector3d& position) {
  if (samples_ > 0 && stamp_ns <= previous_ns_) return std::nullopt;
  std::optional<Eigen::Vector3d> jump;
  if (samples_ > 0) {
    const double dt = 1e-9 * static_cast<double>(stamp_ns - previous_ns_);
    const Eigen::Vector3d motion =
        samples_ > 1 ? Eigen::Vector3d(velocity_ * dt) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d predicted = previous_ + motion;
    const Eigen::Vector3d unexplained = position - predicted;
    if (options_.jump_threshold_m > 0.0 &&
        unexplained.norm() > options_.jump_threshold_m + options_.max_speed_mps * dt) {
      jump = unexplained;
      samples_ = 1;  // the velocity across the jump means nothing
    } else {
      velocity_ = (position - previous_) / dt;
      samples_ = 2;
    }
  } else {
    samples_ = 1;
  }
  previous_ns_ = stamp_ns;
  previous_ = position;
  return jump;
}

}  // namespace auv::mapping
