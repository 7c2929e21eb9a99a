#pragma once
// The simulator's ground-truth files in a run folder (formats in components/simulator/README.md):
//   ground_truth/trajectory.tum   true body pose   "t x y z qx qy qz qw" (TUM; NED, FRD->NED)
//   ground_truth/navigation.tum   navigation estimate, same format (for trajectory comparison)
//   ground_truth/collisions.csv   one line per collision event
//   ground_truth/clearance.csv    t,clearance: hull surface to the world (m, capped at 5 m)
// Lines are flushed as they are written, so a crash loses at most the last line.

#include <Eigen/Geometry>
#include <fstream>
#include <string>

namespace auv::sim {

class GroundTruthLog {
 public:
  /// Creates `<run_dir>/ground_truth/`; throws std::runtime_error naming the path on failure.
  explicit GroundTruthLog(const std::string& run_dir);

  void trajectory(double t, const Eigen::Isometry3d& body_pose);
  void navigation(double t, const Eigen::Isometry3d& estimated_pose);
  void collision(double t, const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                 double penetration, double speed, bool started);
  void clearance(double t, double clearance_m);
  void flush();

 private:
  static void writePose(std::ofstream& out, double t, const Eigen::Isometry3d& pose);
  std::ofstream trajectory_;
  std::ofstream navigation_;
  std::ofstream collisions_;
  std::ofstream clearance_;
};

}  // namespace auv::sim
