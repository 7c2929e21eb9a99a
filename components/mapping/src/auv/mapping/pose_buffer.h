#pragma once
// Time-indexed vehicle poses (from nav/odometry) so each sonar beam is placed with the pose
// at its own timestamp rather than the latest one.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "auv/config/option_table.h"

namespace auv::mapping {

/// A pose of the body (FRD) in the world (NED): position m, orientation body -> world.
struct StampedPose {
  int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// Why lookUp() gave no pose.
enum class PoseLookupStatus {
  OK,
  EMPTY,         ///< no pose received yet
  BEFORE_START,  ///< stamp older than the oldest pose kept (beam came too late)
  AFTER_END,     ///< stamp newer than the newest pose (odometry lags; retry later)
  GAP_TOO_LONG,  ///< the two poses around the stamp are further apart than max_gap_s
};

std::string toString(PoseLookupStatus status);

/// Bounded buffer of poses sorted by time, interpolated at a query time: position linearly,
/// orientation by slerp. Not thread-safe (the component uses it from one executor thread).
class PoseBuffer {
 public:
  struct Options {
    std::size_t capacity = 2000;  ///< poses kept (oldest dropped); 2000 = 40 s at 50 Hz.
    /// s, largest time between two poses that may be interpolated; beyond it the vehicle
    /// may have moved too far for a straight-line pose to be trusted.
    double max_gap_s = 0.5;
    /// s, how far past the newest pose a stamp may lie and still get the newest pose (held);
    /// covers beams stamped a little after the last odometry sample.
    double max_extrapolation_s = 0.0;
    /// The fields with meaning, unit and range, named as the mapping component's parameters
    /// (pose_buffer_length, pose_max_gap, pose_max_extrapolation).
    static const config::OptionTable<Options>& table();
    void check() const;  ///< Throws std::invalid_argument naming the bad field.
  };

  PoseBuffer() : PoseBuffer(Options{}) {}
  explicit PoseBuffer(const Options& options);

  /// Adds a pose. Out-of-order poses are inserted in place; a pose with the same stamp as a
  /// kept one replaces it.
  void add(const StampedPose& pose);
  /// Pose at `stamp_ns`, or nullopt with `status` saying why.
  std::optional<StampedPose> lookUp(int64_t stamp_ns, PoseLookupStatus* status = nullptr) const;

  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  int64_t oldestStampNs() const { return poses_.empty() ? 0 : poses_.front().stamp_ns; }
  int64_t newestStampNs() const { return poses_.empty() ? 0 : poses_.back().stamp_ns; }
  void clear() { poses_.clear(); }

 private:
  Options options_;
  std::deque<StampedPose> poses_;
};

/// Pose at `stamp_ns` between `a` and `b` (linear position, slerp orientation).
StampedPose interpolate(const StampedPose& a, const StampedPose& b, int64_t stamp_ns);

}  // namespace auv::mapping
