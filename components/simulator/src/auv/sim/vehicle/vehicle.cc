#include "auv/sim/vehicle/vehicle.h"

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace auv::sim {

VehicleModel readVehicleModel(const YamlSection& section) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  VehicleModel model;
  std::vector<std::string> known = {"start"};  // the scenario's, read by loadScenario()
  for (const VehicleModel::Field& f : VehicleModel::fields()) {
    known.push_back(f.name);
    std::optional<double> min;
    if (f.min > -kInf) min = f.min;
    std::optional<double> max;
    if (f.max < kInf) max = f.max;
    section.read(f.name, model.*f.member, min, max);  // exclusive bounds: check() below
  }
  section.rejectUnknownKeys(known);
  try {
    model.check();
  } catch (const control::ConfigError& e) {
    throw ConfigError(section.file() + ": " + e.what());  // check() names "vehicle.<field>"
  }
  return model;
}

}  // namespace auv::sim
