#pragma once
// The simulator: stands in for the vehicle's hardware in a world given as a mesh. One thread
// steps the physics at a fixed rate in simulation time and publishes what the real vehicle's
// drivers would: `clock`, `nav/odometry` (drifting dead reckoning), `sonar/beam` (profiler),
// `sonar/scan` (forward-looking multibeam) and `dvl/beams` (the DVL's four bottom returns) when
// the scenario has those sensors,
// plus ground truth for evaluation only (`sim/ground_truth`, `sim/collision`, and files in the
// run folder). It applies `control/thrusters` from the low-level controller.

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "auv/config/option_table.h"
#include "auv/interfaces/component.h"
#include "auv/sim/components/ground_truth_log.h"
#include "auv/sim/components/live_cameras.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/sensors/dvl_beams.h"
#include "auv/sim/sensors/multibeam.h"
#include "auv/sim/sensors/navigation.h"
#include "auv/sim/sensors/profiling_sonar.h"
#include "auv/sim/sensors/sensor_faults.h"
#include "auv/sim/vehicle/vehicle.h"
#include "auv/sim/world/hull_contact.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

class SimulatorComponent : public interfaces::Component {
 public:
  struct Options {
    std::string world = "canyon";   ///< world name (generated on demand) or scenario .yaml path
    int64_t seed = 1;               ///< world generation and sensor noise
    std::string world_cache;        ///< where generated worlds are kept (empty: user cache)
    double real_time_factor = 1.0;  ///< sim seconds per wall second; 0 = as fast as possible
    double physics_rate = 50.0;     ///< Hz (simulation time)
    double odometry_rate = 10.0;    ///< Hz, nav/odometry and sim/ground_truth
    double trajectory_rate = 25.0;  ///< Hz, rows of ground_truth/trajectory.tum
    double thruster_timeout = 1.0;  ///< s, thrusters stop when setpoints stop arriving
    double collision_repeat = 1.0;  ///< s, period of repeated events while a contact lasts
    double duration = 0.0;          ///< s of simulation time before stopping; 0 = unlimited
    /// run folder for ground truth (and the cameras' videos); "auto" (or empty):
    /// auv_runs/<scenario>-<date-time>, replaced by that folder in configure().
    std::string run_dir = "auto";
    /// objective of the mission file written into the run folder
    std::string mission_objective = "visibility";
    /// Live preview frames of the scenario's cameras (live_cameras.h): Hz of simulated time
    /// per camera (0: none), resolution factor, JPEG quality, which cameras (empty: all).
    double camera_live_rate = 0.0;
    double camera_live_scale = 0.25;
    int camera_live_jpeg_quality = 80;
    std::vector<std::string> camera_live_cameras;
    /// Injected sensor faults (sensors/sensor_faults.h): sonar_silent@T+D, ... (empty: none).
    std::vector<std::string> faults;
    /// The fields with meaning, unit and range: the component's parameters come from it.
    static const config::OptionTable<Options>& table();
  };

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// Thread-safe snapshots, for tests and tools.
  VehicleState trueState() const;
  double simulationTime() const;
  uint64_t collisionCount() const { return collisions_.load(); }
  const std::string& runDir() const { return options_.run_dir; }
  const Scenario& scenario() const { return scenario_; }

 private:
  void run();
  void step(double dt);
  double trueAltitude(const VehicleState& state) const;
  void checkCollision(double t, VehicleState& state);
  void publishClock(double t);
  /// Pings the multibeam and the DVL beams when due.
  void pingRangeSensors(double t, const VehicleState& state, bool sonar_silent, bool dvl_lost);

  interfaces::Node* node_ = nullptr;
  Options options_;
  Scenario scenario_;
  std::unique_ptr<Mesh> mesh_;
  std::unique_ptr<RayCaster> world_;
  std::unique_ptr<VehicleDynamics> dynamics_;
  std::unique_ptr<NavigationSimulator> navigation_;
  SensorFaults faults_;
  std::unique_ptr<ProfilingSonar> sonar_;
  std::unique_ptr<Multibeam> multibeam_;  ///< null: the scenario has none
  std::unique_ptr<DvlBeams> dvl_beams_;   ///< null: no dvl_beams section
  std::unique_ptr<GroundTruthLog> log_;
  std::unique_ptr<LiveCameras> live_cameras_;  ///< null: camera_live_rate 0
  HullShape hull_;

  mutable std::mutex state_mutex_;  // state_ and time_ (read by other threads)
  VehicleState state_;
  double time_ = 0.0;

  std::mutex thrust_mutex_;
  ThrusterCommand thrust_;
  double thrust_stamp_ = -1e9;  // sim time the setpoints arrived

  double last_altitude_ = -1.0;
  double roughness_ = 0.0;
  double next_odometry_ = 0.0, next_trajectory_ = 0.0;
  double next_clearance_ = 0.0;
  bool in_contact_ = false;
  double last_collision_event_ = -1e9;
  std::atomic<uint64_t> collisions_{0};

  std::shared_ptr<interfaces::Publisher<msg::Clock>> clock_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> ground_truth_pub_;
  std::shared_ptr<interfaces::Publisher<msg::SonarBeam>> sonar_pub_;
  std::shared_ptr<interfaces::Publisher<msg::PointCloud>> scan_pub_;       ///< sonar/scan
  std::shared_ptr<interfaces::Publisher<msg::PointCloud>> dvl_beams_pub_;  ///< dvl/beams
  std::shared_ptr<interfaces::Publisher<msg::CollisionEvent>> collision_pub_;
  std::shared_ptr<interfaces::Subscription<msg::ThrusterSetpoints>> thrusters_sub_;

  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace auv::sim
