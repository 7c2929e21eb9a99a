#pragma once
// The vehicle's true trajectory as the simulator logs it (<run>/ground_truth/trajectory.tum):
// TUM format, one sample a line, "t x y z qx qy qz qw" (t = sim time s; position m NED; the
// quaternion rotates body FRD into world NED). '#' lines and blank lines are skipped.

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace auv::sim {

struct TimedPose {
  double time = 0;                                                 ///< s, simulation time
  Eigen::Vector3d position{0, 0, 0};                               ///< m NED
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};  ///< body FRD -> world NED
};

class Trajectory {
 public:
  /// At least one sample, times strictly increasing, unit quaternions; throws ConfigError.
  explicit Trajectory(std::vector<TimedPose> samples);

  /// Reads a TUM file. Throws ConfigError naming the file (and line: "file:12: ...") when it
  /// is missing, empty, has a malformed or non-finite line, time going backwards or a
  /// quaternion far from unit length.
  static Trajectory load(const std::string& path);

  double startTime() const { return samples_.front().time; }
  double endTime() const { return samples_.back().time; }
  /// Body -> world at time t: linear in position, slerp in orientation; clamped to the ends.
  Eigen::Isometry3d poseAt(double time) const;
  const std::vector<TimedPose>& samples() const { return samples_; }

 private:
  std::vector<TimedPose> samples_;
};

}  // namespace auv::sim
