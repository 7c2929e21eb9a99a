#include "auv/sim/sensors/sensor_faults.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace auv::sim {
namespace {

struct KindName {
  const char* name;
  SensorFaultKind kind;
};
constexpr KindName kKinds[] = {{"sonar_silent", SensorFaultKind::SONAR_SILENT},
                               {"navigation_silent", SensorFaultKind::NAVIGATION_SILENT},
                               {"dvl_lost", SensorFaultKind::DVL_LOST},
                               {"navigation_jump", SensorFaultKind::NAVIGATION_JUMP}};

/// A finite number filling all of `text`.
double number(const std::string& text, const std::string& entry, const char* what) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value)) {
    throw std::invalid_argument("faults: '" + entry + "': " + what + " '" + text +
                                "' is not a number");
  }
  return value;
}

}  // namespace

SensorFaults SensorFaults::parse(const std::vector<std::string>& lists) {
  // Entries may also come several to a string, separated by spaces (a launch argument).
  std::vector<std::string> entries;
  for (const std::string& list : lists) {
    std::istringstream words(list);
    for (std::string word; words >> word;) entries.push_back(word);
  }
  SensorFaults parsed;
  for (const std::string& entry : entries) {
    const size_t at = entry.find('@');
    if (at == std::string::npos) {
      throw std::invalid_argument("faults: '" + entry +
                                  "': expected KIND@T+D or navigation_jump@T:DX,DY");
    }
    const std::string name = entry.substr(0, at);
    const std::string when = entry.substr(at + 1);
    SensorFault fault;
    bool known = false;
    for (const KindName& k : kKinds) {
      if (name == k.name) {
        fault.kind = k.kind;
        known = true;
      }
    }
    if (!known) {
      throw std::invalid_argument("faults: '" + entry + "': unknown kind '" + name +
                                  "' (sonar_silent, navigation_silent, dvl_lost, "
                                  "navigation_jump)");
    }
    if (fault.kind == SensorFaultKind::NAVIGATION_JUMP) {
      const size_t colon = when.find(':');
      const size_t comma = when.find(',', colon == std::string::npos ? 0 : colon);
      if (colon == std::string::npos || comma == std::string::npos) {
        throw std::invalid_argument("faults: '" + entry + "': expected navigation_jump@T:DX,DY");
      }
      fault.start = number(when.substr(0, colon), entry, "time");
      fault.jump = {number(when.substr(colon + 1, comma - colon - 1), entry, "DX"),
                    number(when.substr(comma + 1), entry, "DY")};
    } else {
      const size_t plus = when.find('+');
      if (plus == std::string::npos) {
        throw std::invalid_argument("faults: '" + entry + "': expected " + name + "@T+D");
      }
      fault.start = number(when.substr(0, plus), entry, "time");
      fault.duration = number(when.substr(plus + 1), entry, "duration");
      if (fault.duration <= 0) {
        throw std::invalid_argument("faults: '" + entry + "': the duration must be > 0");
      }
    }
    if (fault.start < 0) {
      throw std::invalid_argument("faults: '" + entry + "': the time must be >= 0");
    }
    parsed.faults_.push_back(fault);
  }
  return parsed;
}

bool SensorFaults::active(SensorFaultKind kind, double t) const {
  for (const SensorFault& f : faults_) {
    if (f.kind == kind && t >= f.start && t < f.start + f.duration) return true;
  }
  return false;
}

Eigen::Vector2d SensorFaults::navigationOffset(double t) const {
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  for (const SensorFault& f : faults_) {
    if (f.kind == SensorFaultKind::NAVIGATION_JUMP && t >= f.start) offset += f.jump;
  }
  return offset;
}

}  // namespace auv::sim
