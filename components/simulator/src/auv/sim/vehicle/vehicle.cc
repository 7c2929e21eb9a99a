#include "auv/sim/vehicle/vehicle.h"

#include <string>
#include <vector>

namespace auv::sim {

VehicleModel readVehicleModel(const YamlSection& section) {
  VehicleModel model;
  std::vector<std::string> known = {"start"};  // the scenario's, read by loadScenario()
  for (const auto& option : VehicleModel::table()) {
    known.push_back(option.name);
    // Exclusive bounds are left to check() below.
    section.read(option.name, model.*option.member<double>(), option.range.min, option.range.max);
  }
  section.rejectUnknownKeys(known);
  checkInFile(section, model);
  return model;
}

}  // namespace auv::sim
