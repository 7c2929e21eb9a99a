#include "auv/sim/camera/trajectory.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "auv/sim/common/yaml_section.h"

namespace auv::sim {
namespace {

// Normalises a quaternion that is unit up to rounding; rejects anything else, since a
// logged pose must be a rotation.
bool normaliseRotation(Eigen::Quaterniond& q) {
  const double norm = q.norm();
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-3) return false;
  q.normalize();
  return true;
}

}  // namespace

Trajectory::Trajectory(std::vector<TimedPose> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw ConfigError("trajectory: no samples");
  for (size_t i = 0; i < samples_.size(); ++i) {
    TimedPose& s = samples_[i];
    if (!std::isfinite(s.time) || !s.position.allFinite() || !normaliseRotation(s.orientation)) {
      throw ConfigError("trajectory: sample " + std::to_string(i) +
                        ": non-finite value or non-unit quaternion");
    }
    if (i > 0 && !(s.time > samples_[i - 1].time)) {
      throw ConfigError("trajectory: sample " + std::to_string(i) + ": time " +
                        std::to_string(s.time) + " s does not increase");
    }
  }
}

Trajectory Trajectory::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the trajectory file");
  std::vector<TimedPose> samples;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    std::istringstream fields(line);
    std::vector<double> values;
    std::string token;
    while (fields >> token) {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(value)) {
        throw ConfigError(where + "'" + token + "' is not a finite number");
      }
      values.push_back(value);
    }
    if (values.size() != 8) {
      throw ConfigError(where + "expected 8 numbers \"t x y z qx qy qz qw\", got " +
                        std::to_string(values.size()));
    }
    TimedPose pose;
    pose.time = values[0];
    pose.position = {values[1], values[2], values[3]};
    pose.orientation = Eigen::Quaterniond(values[7], values[4], values[5], values[6]);
    if (!normaliseRotation(pose.orientation)) {
      throw ConfigError(where + "the quaternion (qx qy qz qw) is not of unit length");
    }
    if (!samples.empty() && !(pose.time > samples.back().time)) {
      throw ConfigError(
          where + "time " + std::to_string(pose.time) +
          " s does not increase (previous line: " + std::to_string(samples.back().time) + " s)");
    }
    samples.push_back(pose);
  }
  if (samples.empty()) throw ConfigError(path + ": no trajectory samples in the file");
  return Trajectory(std::move(samples));
}

Eigen::Isometry3d Trajectory::poseAt(double time) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (time <= samples_.front().time || samples_.size() == 1) {
    T.linear() = samples_.front().orientation.toRotationMatrix();
    T.translation() = samples_.front().position;
    return T;
  }
  if (time >= samples_.back().time) {
    T.linear() = samples_.back().orientation.toRotationMatrix();
    T.translation() = samples_.back().position;
    return T;
  }
  const auto after = std::upper_bound(samples_.begin(), samples_.end(), time,
                                      [](double t, const TimedPose& s) { return t < s.time; });
  const TimedPose& b = *after;
  const TimedPose& a = *(after - 1);
  const double f = (time - a.time) / (b.time - a.time);
  T.linear() = a.orientation.slerp(f, b.orientation).toRotationMatrix();
  T.translation() = (1.0 - f) * a.position + f * b.position;
  return T;
}

}  // namespace auv::sim
