#pragma once
// The controller closed on the vehicle dynamics, shared by the core tests (controller_test.cc,
// controller_safety_test.cc).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "auv/control/controller.h"

namespace auv::control::test_support {

constexpr double kDt = 0.05;  // s, 20 Hz like the component

// The vehicle, its controller and a flat seabed, stepped together.
struct ClosedLoop {
  explicit ClosedLoop(const ControllerOptions& controller_options = {},
                      const VehicleModel& vehicle_options = {})
      : dynamics(vehicle_options), controller(controller_options) {}

  // Steps `seconds`; navigation is sent unless `navigation` is false. `each` sees every step.
  void run(double seconds, const std::function<void()>& each = {}, bool navigation = true) {
    const int steps = static_cast<int>(std::lround(seconds / kDt));
    for (int i = 0; i < steps; ++i) {
      if (navigation) {
        const double altitude = seabed_depth > 0 ? seabed_depth - state.position.z() : -1.0;
        ControllerNavigation nav = ControllerNavigation::fromState(state, altitude, t);
        if (filter) filter(nav);
        controller.setNavigation(nav, t);
      }
      last = controller.update(t);
      for (double c : {last.port, last.starboard, last.vertical}) {
        ASSERT_TRUE(std::isfinite(c));
        ASSERT_LE(std::abs(c), 1.0);
      }
      dynamics.step(state, last, kDt);
      t += kDt;
      if (each) each();
    }
  }
  // Runs until `done()` or `limit` s; returns the time it took (or `limit`).
  double runUntil(const std::function<bool()>& done, double limit) {
    const double start = t;
    while (t - start < limit && !done()) run(kDt);
    return t - start;
  }
  CommandResult send(const ControlCommand& command) { return controller.setCommand(command, t); }
  const ControllerStatusReport& status() const { return controller.status(); }

  VehicleDynamics dynamics;
  LowLevelController controller;
  VehicleState state;
  ThrusterCommand last;
  double seabed_depth = -1;                           // m; <= 0: altitude unknown
  std::function<void(ControllerNavigation&)> filter;  // turns the truth into an estimate
  double t = 0;
};

inline ControlCommand waypoint(uint64_t id, const Eigen::Vector3d& target, double speed = 0.8,
                               double tolerance = 1.0) {
  ControlCommand c;
  c.command_id = id;
  c.mode = ControlMode::WAYPOINT;
  c.position = target;
  c.surge_speed = speed;
  c.tolerance = tolerance;
  return c;
}

inline ControlCommand setpoint(uint64_t id, double heading, double depth, double speed) {
  ControlCommand c;
  c.command_id = id;
  c.mode = ControlMode::SETPOINT;
  c.heading = heading;
  c.depth = depth;
  c.surge_speed = speed;
  return c;
}

inline double horizontalDistance(const VehicleState& s, const Eigen::Vector3d& p) {
  return (p - s.position).head<2>().norm();
}

}  // namespace auv::control::test_support
