// Vehicle dynamics against the analytic solutions of its own drag model.
#include "auv/control/vehicle_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace auv::control {
namespace {

constexpr double kDt = 0.05;  // s, the simulator's step

// Runs `seconds` of constant `command` from `state`; calls `each(state)` after every step.
template <class Each>
void run(VehicleDynamics& dynamics, VehicleState& state, const ThrusterCommand& command,
         double seconds, Each each) {
  const int steps = static_cast<int>(std::lround(seconds / kDt));
  for (int i = 0; i < steps; ++i) {
    dynamics.step(state, command, kDt);
    each(state);
  }
}

void run(VehicleDynamics& dynamics, VehicleState& state, const ThrusterCommand& command,
         double seconds) {
  run(dynamics, state, command, seconds, [](const VehicleState&) {});
}

// Speed from rest under a constant force with linear + quadratic drag, solved exactly:
// m du/dt = -b (u - u1)(u - u2), with u1 > 0 > u2 the roots of b u^2 + a u - F = 0.
double analyticSpeed(double force, double mass, double a, double b, double t) {
  const double u1 = terminalSpeed(force, a, b);
  const double u2 = (-a - std::sqrt(a * a + 4 * b * force)) / (2 * b);
  const double r = (-u2 / u1) * std::exp(b * (u1 - u2) * t / mass);
  return (r * u1 + u2) / (1 + r);
}

TEST(VehicleDynamicsTest, FullThrustReachesTheTerminalSurgeSpeedOfTheDragModel) {
  const VehicleModel options;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  run(dynamics, state, {1.0, 1.0, 0.0}, 60.0);
  const double expected = terminalSpeed(2 * options.max_thrust_forward, options.drag_linear_surge,
                                        options.drag_quadratic_surge);
  EXPECT_NEAR(state.surge, expected, 0.02 * expected);
  // The design targets of the defaults: ~1.2 m/s flat out.
  EXPECT_NEAR(expected, 1.2, 0.05);
  // Cruise 0.5-1 m/s at moderate thrust: the thrust needed stays below 75 % of full.
  EXPECT_LT(options.surgeDrag(1.0), 0.75 * 2 * options.max_thrust_forward);
  EXPECT_LT(options.surgeDrag(0.5), 0.25 * 2 * options.max_thrust_forward);
  // Straight north, no turn.
  EXPECT_DOUBLE_EQ(state.yaw, 0.0);
  EXPECT_DOUBLE_EQ(state.position.y(), 0.0);
  EXPECT_GT(state.position.x(), 50.0);
}

TEST(VehicleDynamicsTest, SurgeTransientFollowsTheAnalyticSolution) {
  VehicleModel options;
  options.thruster_time_constant = 0.0;  // the analytic solution assumes a force step
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  const double force = 2 * options.thrustForCommand(0.6);
  double t = 0;
  for (double checkpoint : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0}) {
    run(dynamics, state, {0.6, 0.6, 0.0}, checkpoint - t);
    t = checkpoint;
    const double expected = analyticSpeed(force, options.surgeMass(), options.drag_linear_surge,
                                          options.drag_quadratic_surge, t);
    EXPECT_NEAR(state.surge, expected, 0.02 * expected) << "t = " << t;
  }
}

TEST(VehicleDynamicsTest, LinearDragTimeConstantIsMassOverDrag) {
  VehicleModel options;
  options.thruster_time_constant = 0.0;
  options.drag_quadratic_surge = 0.0;
  options.drag_linear_surge = 20.0;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  const double tau = options.surgeMass() / options.drag_linear_surge;  // 2.85 s
  const double terminal = 2 * options.thrustForCommand(0.2) / options.drag_linear_surge;
  // Time to reach 1 - 1/e of the terminal speed.
  double t = 0;
  while (state.surge < (1 - std::exp(-1.0)) * terminal && t < 60) {
    dynamics.step(state, {0.2, 0.2, 0.0}, kDt);
    t += kDt;
  }
  EXPECT_NEAR(t, tau, 0.02 * tau + kDt);
}

TEST(VehicleDynamicsTest, ThrustRespondsWithTheFirstOrderTimeConstant) {
  const VehicleModel options;  // 0.2 s
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  dynamics.step(state, {1.0, -1.0, 1.0}, options.thruster_time_constant);
  const double fraction = 1 - std::exp(-1.0);
  EXPECT_NEAR(dynamics.thrust()[0], fraction * options.max_thrust_forward, 1e-9);
  EXPECT_NEAR(dynamics.thrust()[1], -fraction * options.max_thrust_reverse, 1e-9);
  EXPECT_NEAR(dynamics.thrust()[2], fraction * options.max_thrust_forward, 1e-9);
  // Commands beyond +-1 saturate.
  run(dynamics, state, {3.0, -7.0, -2.0}, 5.0);
  EXPECT_NEAR(dynamics.thrust()[0], options.max_thrust_forward, 1e-6);
  EXPECT_NEAR(dynamics.thrust()[1], -options.max_thrust_reverse, 1e-6);
  EXPECT_NEAR(dynamics.thrust()[2], -options.max_thrust_reverse, 1e-6);
}

TEST(VehicleDynamicsTest, DifferentialThrustTurnsAtTheTerminalYawRate) {
  const VehicleModel options;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  // Port forward, starboard astern: bow to starboard, i.e. positive yaw (towards east).
  dynamics.step(state, {1.0, -1.0, 0.0}, 1.0);
  EXPECT_GT(state.yaw, 0.0);
  run(dynamics, state, {1.0, -1.0, 0.0}, 30.0);
  const double expected =
      terminalSpeed(options.maxYawMoment(), options.drag_linear_yaw, options.drag_quadratic_yaw);
  EXPECT_NEAR(state.yaw_rate, expected, 0.02 * expected);
  EXPECT_NEAR(expected, 0.5, 0.05);  // design target of the defaults
  // The mirror image turns the other way at the same rate.
  VehicleDynamics mirrored(options);
  VehicleState other;
  other.position.z() = 5.0;
  run(mirrored, other, {-1.0, 1.0, 0.0}, 31.0);
  EXPECT_NEAR(other.yaw_rate, -state.yaw_rate, 1e-9);
}

TEST(VehicleDynamicsTest, SymmetricThrustGivesNoYaw) {
  VehicleDynamics dynamics{VehicleModel()};
  VehicleState state;
  state.position.z() = 5.0;
  state.yaw = 0.7;
  run(dynamics, state, {0.6, 0.6, 0.2}, 30.0);
  EXPECT_DOUBLE_EQ(state.yaw, 0.7);
  EXPECT_DOUBLE_EQ(state.yaw_rate, 0.0);
  EXPECT_DOUBLE_EQ(state.sway, 0.0);
  // It went along its heading.
  EXPECT_NEAR(std::atan2(state.position.y(), state.position.x()), 0.7, 1e-9);
}

TEST(VehicleDynamicsTest, TurningWhileMovingSlipsOutwards) {
  VehicleDynamics dynamics{VehicleModel()};
  VehicleState state;
  state.position.z() = 5.0;
  run(dynamics, state, {1.0, 0.4, 0.0}, 40.0);
  EXPECT_GT(state.yaw_rate, 0.0);  // turning to starboard
  EXPECT_LT(state.sway, 0.0);      // the centrifugal effect pushes it to port
  EXPECT_LT(std::abs(state.sway), 0.5 * state.surge);
  // A steady circle: speed bounded by the straight-line terminal speed.
  EXPECT_LT(std::hypot(state.surge, state.sway), 1.25);
}

TEST(VehicleDynamicsTest, VerticalThrustDivesAtTheTerminalHeaveSpeed) {
  const VehicleModel options;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 1.0;
  run(dynamics, state, {0.0, 0.0, 1.0}, 30.0);
  const double expected = terminalSpeed(options.max_thrust_forward - options.net_buoyancy,
                                        options.drag_linear_heave, options.drag_quadratic_heave);
  EXPECT_NEAR(state.heave, expected, 0.02 * expected);
  EXPECT_GT(state.position.z(), 1.0 + 0.8 * expected * 30.0);
}

TEST(VehicleDynamicsTest, PositiveBuoyancyRisesSlowlyAndStopsAtTheSurface) {
  const VehicleModel options;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 3.0;
  double min_depth = 3.0;
  run(dynamics, state, {0.0, 0.0, 0.0}, 20.0,
      [&](const VehicleState& s) { min_depth = std::min(min_depth, s.position.z()); });
  const double rise =
      terminalSpeed(options.net_buoyancy, options.drag_linear_heave, options.drag_quadratic_heave);
  EXPECT_NEAR(state.heave, -rise, 0.02 * rise);
  EXPECT_GT(rise, 0.02);  // "slowly": centimetres per second
  EXPECT_LT(rise, 0.1);
  // Full thrust up: the surface is a hard limit, never above it.
  run(dynamics, state, {0.0, 0.0, -1.0}, 60.0,
      [&](const VehicleState& s) { min_depth = std::min(min_depth, s.position.z()); });
  EXPECT_EQ(min_depth, 0.0);
  EXPECT_EQ(state.position.z(), 0.0);
  EXPECT_GE(state.heave, 0.0);
  // And it can dive again from there.
  run(dynamics, state, {0.0, 0.0, 1.0}, 5.0);
  EXPECT_GT(state.position.z(), 0.2);
}

TEST(VehicleDynamicsTest, StepSizeDoesNotChangeTheTrajectory) {
  const VehicleModel options;
  VehicleDynamics coarse(options), fine(options);
  VehicleState a, b;
  a.position.z() = b.position.z() = 5.0;
  const ThrusterCommand turn{1.0, 0.2, 0.5};
  for (int i = 0; i < 200; ++i) coarse.step(a, turn, 0.05);
  for (int i = 0; i < 10000; ++i) fine.step(b, turn, 0.001);
  EXPECT_LT((a.position - b.position).norm(), 0.01 * b.position.norm());
  EXPECT_NEAR(a.yaw, b.yaw, 0.01);
  // Very large steps stay bounded (sub-stepped), and NaN commands count as zero.
  VehicleDynamics big(options);
  VehicleState c;
  c.position.z() = 5.0;
  big.step(c, {1.0, 1.0, std::nan("")}, 10.0);
  EXPECT_TRUE(c.position.allFinite());
  EXPECT_LE(c.surge, options.max_surge_speed);
  EXPECT_THROW(big.step(c, {}, -0.1), std::invalid_argument);
}

TEST(VehicleDynamicsTest, SpeedLimitsAreHard) {
  VehicleModel options;
  options.max_surge_speed = 0.5;
  options.max_yaw_rate = 0.2;
  VehicleDynamics dynamics(options);
  VehicleState state;
  state.position.z() = 5.0;
  run(dynamics, state, {1.0, 1.0, 0.0}, 20.0);
  EXPECT_DOUBLE_EQ(state.surge, 0.5);
  run(dynamics, state, {1.0, -1.0, 0.0}, 20.0);
  EXPECT_DOUBLE_EQ(state.yaw_rate, 0.2);
}

TEST(VehicleModelTest, CheckNamesTheField) {
  VehicleModel options;
  options.mass = -1;
  try {
    options.check();
    FAIL() << "negative mass accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vehicle.mass"), std::string::npos) << e.what();
  }
  options = VehicleModel();
  options.drag_linear_yaw = options.drag_quadratic_yaw = 0;
  EXPECT_THROW(options.check(), ConfigError);
  options = VehicleModel();
  options.thruster_time_constant = std::nan("");
  EXPECT_THROW(VehicleDynamics{options}, ConfigError);
}

}  // namespace
}  // namespace auv::control
