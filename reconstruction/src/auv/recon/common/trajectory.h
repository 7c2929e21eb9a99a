#pragma once
// The vehicle's navigation as a TUM trajectory "t x y z qx qy qz qw" (the simulator's
// <run>/ground_truth/navigation.tum, the vehicle's estimate; or trajectory.tum, the truth):
// positions by time, for the stages that use navigation (match: pairs that cannot overlap;
// sfm: metric scale and gravity).

#include <filesystem>
#include <vector>

#include <Eigen/Core>

namespace auv::recon {

struct TimedPosition {
  double time = 0;  ///< s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

/// A TUM trajectory file, sorted by time. Throws std::runtime_error naming the file and line
/// for a malformed line; an empty or missing file is an error too.
std::vector<TimedPosition> readTumTrajectory(const std::filesystem::path& file);

/// Linear interpolation; false outside the trajectory's time span.
bool positionAt(const std::vector<TimedPosition>& trajectory, double time,
                Eigen::Vector3d& position);

}  // namespace auv::recon
