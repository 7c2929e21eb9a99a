#pragma once
// Text shared by the executive's sources (mission_executive.cc, mission_recovery.cc).

#include <sstream>
#include <string>

namespace auv::mission {

inline std::string formatSeconds(double seconds) {
  std::ostringstream out;
  out.precision(2);
  out << std::fixed << seconds << " s";
  return out.str();
}

}  // namespace auv::mission
