// Fuzz harness: the simulator's `faults` parameter (SensorFaults::parse: KIND@T+D and
// navigation_jump@T:DX,DY, several to a string separated by spaces), each line of the input one
// entry of the string list, and the queries the simulator makes of the parsed faults. A clear
// error is a std::invalid_argument naming the entry; anything else (a crash, a sanitizer report,
// another exception) is a bug.
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/sim/sensors/sensor_faults.h"

using auv::sim::SensorFaultKind;
using auv::sim::SensorFaults;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> entries;
  std::istringstream lines(input);
  for (std::string line; std::getline(lines, line);) entries.push_back(line);
  SensorFaults faults;
  try {
    faults = SensorFaults::parse(entries);
  } catch (const std::invalid_argument&) {
    return 0;
  }
  for (const auto& fault : faults.faults()) {
    for (const double t : {fault.start, fault.start + fault.duration, 0.0}) {
      faults.active(fault.kind, t);
      faults.navigationOffset(t);
    }
  }
  return 0;
}

/// Every kind of fault of sensor_faults.h, one to a string and several to a string.
std::vector<std::string> auvFuzzSeeds() {
  return {"sonar_silent@30+10", "navigation_silent@12.5+4\ndvl_lost@0+1e2",
          "navigation_jump@60:5,-3",
          "sonar_silent@1+2 navigation_jump@3:0.5,0.25 dvl_lost@4+5\nnavigation_silent@6+7", ""};
}
