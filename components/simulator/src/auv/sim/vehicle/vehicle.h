#pragma once
// The simulated vehicle is the one the controller models: its state, thruster setpoints,
// physical parameters and dynamics come from auv_control (auv/control/vehicle_model.h), so the
// simulator integrates exactly the model the controller's feed-forward assumes. This header
// brings them into auv::sim and reads the scenario's `vehicle:` section.

#include "auv/control/vehicle_model.h"
#include "auv/sim/common/yaml_section.h"

namespace auv::sim {

using control::terminalSpeed;
using control::ThrusterCommand;
using control::VehicleDynamics;
using control::VehicleModel;
using control::VehicleState;
using control::wrapAngle;

/// Reads the scenario's `vehicle:` section strictly (keys = VehicleModel's field names; `start`
/// is allowed and left to the scenario) and checks the result. Throws ConfigError naming file
/// and field.
VehicleModel readVehicleModel(const YamlSection& section);

}  // namespace auv::sim
