#include "auv/sim/components/ground_truth_log.h"

#include <filesystem>
#include <iomanip>
#include <stdexcept>

namespace auv::sim {
namespace {

std::ofstream openOrThrow(const std::filesystem::path& path, const char* header) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot create the file");
  out << header;
  out << std::fixed << std::setprecision(6);
  return out;
}

}  // namespace

GroundTruthLog::GroundTruthLog(const std::string& run_dir) {
  const std::filesystem::path dir = std::filesystem::path(run_dir) / "ground_truth";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create the folder: " + ec.message());
  trajectory_ = openOrThrow(dir / "trajectory.tum",
                            "# true body pose: t[s sim] x y z[m NED] qx qy qz qw (FRD->NED)\n");
  navigation_ =
      openOrThrow(dir / "navigation.tum",
                  "# navigation estimate: t[s sim] x y z[m NED] qx qy qz qw (FRD->NED)\n");
  collisions_ = openOrThrow(dir / "collisions.csv",
                            "t,x,y,z,normal_x,normal_y,normal_z,penetration,speed,started\n");
  clearance_ = openOrThrow(dir / "clearance.csv", "t,clearance\n");
}

void GroundTruthLog::writePose(std::ofstream& out, double t, const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  const Eigen::Vector3d& p = pose.translation();
  out << t << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' '
      << q.z() << ' ' << q.w() << '\n';
}

void GroundTruthLog::trajectory(double t, const Eigen::Isometry3d& body_pose) {
  writePose(trajectory_, t, body_pose);
}

void GroundTruthLog::clearance(double t, double clearance_m) {
  clearance_ << t << ',' << clearance_m << '\n';
}

void GroundTruthLog::navigation(double t, const Eigen::Isometry3d& estimated_pose) {
  writePose(navigation_, t, estimated_pose);
}

void GroundTruthLog::collision(double t, const Eigen::Vector3d& point,
                               const Eigen::Vector3d& normal, double penetration, double speed,
                               bool started) {
  collisions_ << t << ',' << point.x() << ',' << point.y() << ',' << point.z() << ',' << normal.x()
              << ',' << normal.y() << ',' << normal.z() << ',' << penetration << ',' << speed << ','
              << (started ? 1 : 0) << '\n';
  collisions_.flush();
  clearance_.flush();
}

void GroundTruthLog::flush() {
  trajectory_.flush();
  navigation_.flush();
  collisions_.flush();
  clearance_.flush();
}

}  // namespace auv::sim
