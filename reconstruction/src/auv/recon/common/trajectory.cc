#include "auv/recon/common/trajectory.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auv::recon {

std::vector<TimedPosition> readTumTrajectory(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read the navigation trajectory");
  std::vector<TimedPosition> trajectory;
  std::string line;
  for (size_t number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    TimedPosition p;
    double q[4];
    if (!(fields >> p.time >> p.position.x() >> p.position.y() >> p.position.z() >> q[0] >> q[1] >>
          q[2] >> q[3]) ||
        !std::isfinite(p.time) || !p.position.allFinite()) {
      throw std::runtime_error(file.string() + ":" + std::to_string(number) +
                               ": not a TUM line 't x y z qx qy qz qw'");
    }
    trajectory.push_back(p);
  }
  if (trajectory.empty()) throw std::runtime_error(file.string() + ": no poses");
  std::stable_sort(trajectory.begin(), trajectory.end(),
                   [](const TimedPosition& a, const TimedPosition& b) { return a.time < b.time; });
  return trajectory;
}

bool positionAt(const std::vector<TimedPosition>& trajectory, double time,
                Eigen::Vector3d& position) {
  if (trajectory.empty() || time < trajectory.front().time || time > trajectory.back().time) {
    return false;
  }
  auto after = std::lower_bound(trajectory.begin(), trajectory.end(), time,
                                [](const TimedPosition& p, double t) { return p.time < t; });
  if (after == trajectory.begin()) {
    position = after->position;
    return true;
  }
  const auto before = after - 1;
  const double span = after->time - before->time;
  const double f = span > 0 ? (time - before->time) / span : 0.0;
  position = (1 - f) * before->position + f * after->position;
  return true;
}

}  // namespace auv::recon
