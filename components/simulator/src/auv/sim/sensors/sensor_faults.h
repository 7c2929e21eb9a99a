#pragma once
// Sensor faults injected into a simulation (docs/reliability.md, the fault campaign): windows
// of simulated time in which a sensor is silent, and jumps of the navigation estimate. Given
// as the simulator's `faults` parameter, one fault per entry:
//
//   sonar_silent@T+D        no sonar/beam, sonar/scan from T for D seconds
//   navigation_silent@T+D   no nav/odometry (the mission sees stale navigation)
//   dvl_lost@T+D            the DVL loses bottom lock: navigation dead-reckons, no altitude,
//                           no dvl/beams
//   navigation_jump@T:DX,DY the estimate jumps by (DX, DY) m at T and keeps the offset (a
//                           GPS-like reset that moves the vehicle's idea of where it is)
//
// T and D in simulated seconds since the simulation started.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace auv::sim {

enum class SensorFaultKind { SONAR_SILENT, NAVIGATION_SILENT, DVL_LOST, NAVIGATION_JUMP };

struct SensorFault {
  SensorFaultKind kind = SensorFaultKind::SONAR_SILENT;
  double start = 0.0;                              ///< s, simulated
  double duration = 0.0;                           ///< s (windows only)
  Eigen::Vector2d jump = Eigen::Vector2d::Zero();  ///< m north, east (jumps only)
};

class SensorFaults {
 public:
  SensorFaults() = default;
  /// Parses the entries (syntax above; a string may hold several separated by spaces, an
  /// empty one none). Throws std::invalid_argument naming the entry and what is wrong with it.
  static SensorFaults parse(const std::vector<std::string>& entries);

  /// Whether a window of `kind` covers simulated time `t`.
  bool active(SensorFaultKind kind, double t) const;
  /// The sum of the jumps that happened at or before `t`.
  Eigen::Vector2d navigationOffset(double t) const;
  bool empty() const { return faults_.empty(); }
  const std::vector<SensorFault>& faults() const { return faults_; }

 private:
  std::vector<SensorFault> faults_;
};

}  // namespace auv::sim
