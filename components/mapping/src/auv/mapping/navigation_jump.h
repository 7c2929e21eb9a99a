#pragma once
// Navigation jumps: a navigation estimate that is reset (a GPS fix at the surface, a USBL
// update, a filter restart) moves the vehicle's position by metres between two samples. Every
// return placed afterwards lands shifted against the map built before, and the planner then
// sees walls twice or no way through. NavigationJumpDetector tells such a step apart from
// motion: the step minus the motion predicted from the previous two samples, longer than the
// threshold plus what the vehicle's top speed allows in the time between them (so a long
// navigation gap is never taken for a jump). No DDS: the mapping component feeds it.

#include <Eigen/Core>
#include <cstdint>
#include <optional>

#include "auv/config/option_table.h"

namespace auv::mapping {

class NavigationJumpDetector {
 public:
  /// Declared by the mapping component with the prefix "navigation_".
  struct Options {
    double jump_threshold_m = 1.0;  ///< unexplained step that counts as a jump; 0: never
    double max_speed_mps = 2.5;     ///< the vehicle's top speed (bounds real motion in a gap)
    /// The map moved with a jump takes this times its log-odds: the step is known only from
    /// two samples, so the vehicle's new returns should override what is slightly off.
    double log_odds_scale = 0.5;
    static const config::OptionTable<Options>& table();
    void check() const;  ///< Throws std::invalid_argument naming the field.
  };

  explicit NavigationJumpDetector(const Options& options);

  /// A navigation position (world frame) at `stamp_ns`, in stamp order. Returns the jump (the
  /// unexplained step, world frame) when this sample jumped; nullopt otherwise. Older or
  /// repeated stamps are ignored.
  std::optional<Eigen::Vector3d> add(int64_t stamp_ns, const Eigen::Vector3d& position);
  /// Forgets the history (the next two samples only seed it).
  void reset() { samples_ = 0; }
  const Options& options() const { return options_; }

 private:
  Options options_;
  int samples_ = 0;  // of the two kept: 0, 1 or 2
  int64_t previous_ns_ = 0;
  Eigen::Vector3d previous_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();  // m/s, from the last two samples
};

}  // namespace auv::mapping
