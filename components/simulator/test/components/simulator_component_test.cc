// The simulator component on real DDS (domains 190..199): it publishes clock,
// odometry and sonar (and the multibeam's sonar/scan and dvl/beams when the scenario has them);
// thrusters move the vehicle; driving into a wall publishes a collision event and logs it; bad
// worlds and sensor sections are refused naming the file.
#include "auv/sim/components/simulator_component.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

#include "../core/test_meshes.h"
#include "auv/interfaces/executor.h"
#include "auv/sim/camera/camera_model.h"

namespace auv::sim {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::NodeOptions;
using interfaces::nodeOptions;
using interfaces::Vendor;
namespace fs = std::filesystem;

class SimulatorComponentTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("auv_sim_component_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // A wall 6 m north of the start (mesh z-up: x north), 20 m wide and 10 m deep.
    Mesh wall = test::box({6, -10, -10}, {7, 10, 0});
    saveMesh(wall, (dir_ / "wall.ply").string());
    scenario_ = (dir_ / "wall.yaml").string();
    std::ofstream(scenario_) << "name: wall\n"
                                "world: {mesh: wall.ply, seabed_depth: 10}\n"
                                "water: {visibility: 5}\n"
                                "vehicle: {start: {position: [0, 0, 3], yaw_deg: 0}}\n"
                                "sonar: {max_range: 20}\n";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::vector<std::string> params(double rtf = 4.0) const {
    return {"world:=" + scenario_, "run_dir:=" + (dir_ / "run").string(),
            "real_time_factor:=" + std::to_string(rtf)};
  }
  fs::path dir_;
  std::string scenario_;
};

TEST_F(SimulatorComponentTest, PublishesClockOdometryAndSonarAcrossVendors) {
  Node sim_node("simulator", nodeOptions(Vendor::CYCLONEDDS, 190, params()));
  Node probe("probe", nodeOptions(Vendor::FASTDDS, 190));
  SimulatorComponent sim;
  sim.configure(sim_node);
  int clocks = 0, odometry = 0, echoes = 0, beams = 0;
  double last_clock = 0;
  bool clock_monotonic = true;
  auto c = probe.createSubscription<msg::Clock>(
      "clock", interfaces::clockQos(),
      std::function<void(const msg::Clock&)>([&](const msg::Clock& m) {
        const double t = m.sim_time().sec() + m.sim_time().nanosec() * 1e-9;
        clock_monotonic = clock_monotonic && t > last_clock;
        last_clock = t;
        ++clocks;
      }));
  auto o = probe.createSubscription<msg::Odometry>(
      "nav/odometry", interfaces::stateQos(),
      std::function<void(const msg::Odometry&)>([&](const msg::Odometry& m) {
        EXPECT_NEAR(m.pose().pose().position().z(), 3.0, 0.5);
        ++odometry;
      }));
  auto s = probe.createSubscription<msg::SonarBeam>(
      "sonar/beam", interfaces::sensorDataQos(),
      std::function<void(const msg::SonarBeam&)>([&](const msg::SonarBeam& m) {
        ++beams;
        if (m.ranges().empty()) return;
        // Every echo is the wall (6 m ahead) or farther; none closer than the wall can be.
        EXPECT_GE(m.ranges()[0], 5.0f);
        ++echoes;
      }));
  interfaces::Executor executor;
  executor.add(sim_node);
  executor.add(probe);
  sim.activate();
  EXPECT_TRUE(executor.spinUntil([&] { return odometry >= 10 && echoes >= 3; }, 30s))
      << "odometry " << odometry << " beams " << beams << " echoes " << echoes;
  sim.deactivate();
  EXPECT_GT(clocks, 20);
  EXPECT_TRUE(clock_monotonic);
  // Ground truth trajectory was written while running.
  std::ifstream trajectory(dir_ / "run" / "ground_truth" / "trajectory.tum");
  std::string line;
  int rows = 0;
  while (std::getline(trajectory, line)) rows += line.empty() || line[0] == '#' ? 0 : 1;
  EXPECT_GT(rows, 10);
  EXPECT_TRUE(fs::exists(dir_ / "run" / "scenario.yaml"));
}

TEST_F(SimulatorComponentTest, ThrustersDriveTheVehicleIntoTheWallAndTheCollisionIsReported) {
  Node sim_node("simulator", nodeOptions(Vendor::FASTDDS, 191, params(5.0)));
  Node pilot("pilot", nodeOptions(Vendor::CYCLONEDDS, 191));
  SimulatorComponent sim;
  sim.configure(sim_node);
  auto thrusters = pilot.createPublisher<msg::ThrusterSetpoints>("control/thrusters",
                                                                 interfaces::sensorDataQos());
  std::vector<msg::CollisionEvent> events;
  auto collisions = pilot.createSubscription<msg::CollisionEvent>(
      "sim/collision", interfaces::commandQos(),
      std::function<void(const msg::CollisionEvent&)>(
          [&](const msg::CollisionEvent& e) { events.push_back(e); }));
  interfaces::Executor executor;
  executor.add(sim_node);
  executor.add(pilot);
  sim.activate();
  msg::ThrusterSetpoints full;
  full.port(0.8);
  full.starboard(0.8);
  auto timer = pilot.createTimer(0.05, [&] { thrusters->publish(full); });
  ASSERT_TRUE(executor.spinUntil([&] { return !events.empty(); }, 60s))
      << "no collision; vehicle at " << sim.trueState().position.transpose();
  sim.deactivate();
  const msg::CollisionEvent& first = events.front();
  EXPECT_TRUE(first.started());
  EXPECT_NEAR(first.contact_point().x(), 6.0, 0.05);  // the wall's face
  EXPECT_NEAR(first.contact_normal().x(), -1.0, 0.05);
  EXPECT_GT(first.speed(), 0.2);
  // The vehicle is stopped by the wall, not through it.
  EXPECT_LT(sim.trueState().position.x(), 6.0 - 0.7);
  std::ifstream csv(dir_ / "run" / "ground_truth" / "collisions.csv");
  std::string header, row;
  std::getline(csv, header);
  ASSERT_TRUE(static_cast<bool>(std::getline(csv, row)));
  EXPECT_EQ(row.back(), '1');  // started
}

TEST_F(SimulatorComponentTest, AStartInsideTheWorldIsRefusedNamingTheScenario) {
  std::ofstream(scenario_) << "world: {mesh: wall.ply}\n"
                              "vehicle: {start: {position: [6.5, 0, 3]}}\n";
  Node node("simulator", nodeOptions(Vendor::CYCLONEDDS, 192, params()));
  SimulatorComponent sim;
  try {
    sim.configure(node);
    FAIL() << "started inside the wall";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("wall.yaml: vehicle.start"), std::string::npos)
        << e.what();
  }
}

TEST_F(SimulatorComponentTest, AnUnknownWorldNameListsTheKnownWorlds) {
  Node node("simulator", nodeOptions(Vendor::CYCLONEDDS, 193, {"world:=canyn"}));
  SimulatorComponent sim;
  try {
    sim.configure(node);
    FAIL() << "accepted world 'canyn'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("canyon"), std::string::npos) << e.what();
  }
}

// Counts what arrives on sonar/scan and dvl/beams (and nav/odometry, to know time passed).
struct RangeSensorProbe {
  explicit RangeSensorProbe(Node& node) {
    scan = node.createSubscription<msg::PointCloud>(
        "sonar/scan", interfaces::sensorDataQos(),
        std::function<void(const msg::PointCloud&)>([this](const msg::PointCloud& m) {
          ++scans;
          frames_ok = frames_ok && m.header().frame_id() == "base_link";
          for (const auto& p : m.points()) scan_returns += p.intensity() > 0.0f ? 1 : 0;
        }));
    dvl = node.createSubscription<msg::PointCloud>(
        "dvl/beams", interfaces::sensorDataQos(),
        std::function<void(const msg::PointCloud&)>([this](const msg::PointCloud& m) {
          ++dvl_pings;
          frames_ok = frames_ok && m.header().frame_id() == "base_link";
          const Eigen::Vector3d origin(m.sensor_origin().position().x(),
                                       m.sensor_origin().position().y(),
                                       m.sensor_origin().position().z());
          for (const auto& p : m.points()) {
            dvl_ranges.push_back((Eigen::Vector3d(p.x(), p.y(), p.z()) - origin).norm());
          }
        }));
    odometry = node.createSubscription<msg::Odometry>(
        "nav/odometry", interfaces::stateQos(),
        std::function<void(const msg::Odometry&)>([this](const msg::Odometry&) { ++odom; }));
  }
  int scans = 0, scan_returns = 0, dvl_pings = 0, odom = 0;
  bool frames_ok = true;
  std::vector<double> dvl_ranges;
  std::shared_ptr<interfaces::Subscription<msg::PointCloud>> scan, dvl;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry;
};

TEST_F(SimulatorComponentTest, PublishesMultibeamScansAndDvlBeamsWhenTheScenarioHasThem) {
  // The vehicle 3 m deep over a seabed at 10 m, the wall 6 m ahead; the DVL head 0.2 m below
  // the body's origin sees the seabed 6.8 m below through beams 30 deg from the vertical.
  std::ofstream(scenario_, std::ios::app) << "multibeam: {beams: 64, rows: 2, rate: 10}\n"
                                             "dvl_beams: {range_noise: 0}\n";
  Node sim_node("simulator", nodeOptions(Vendor::CYCLONEDDS, 194, params()));
  Node probe_node("probe", nodeOptions(Vendor::FASTDDS, 194));
  SimulatorComponent sim;
  sim.configure(sim_node);
  RangeSensorProbe probe(probe_node);
  interfaces::Executor executor;
  executor.add(sim_node);
  executor.add(probe_node);
  sim.activate();
  EXPECT_TRUE(executor.spinUntil([&] { return probe.scans >= 5 && probe.dvl_pings >= 5; }, 30s))
      << "scans " << probe.scans << " DVL pings " << probe.dvl_pings;
  sim.deactivate();
  EXPECT_TRUE(probe.frames_ok);
  EXPECT_GT(probe.scan_returns, 0);  // the seabed and the wall ahead
  ASSERT_FALSE(probe.dvl_ranges.empty());
  const double depth = sim.trueState().position.z();  // it barely moves without thrust
  for (double range : probe.dvl_ranges) {
    EXPECT_NEAR(range, (10.0 - depth - 0.2) / std::cos(M_PI / 6), 0.3);
  }
}

TEST_F(SimulatorComponentTest, NoScansOrDvlBeamsWithoutTheSections) {
  std::ofstream(scenario_, std::ios::app) << "multibeam: {enabled: false}\n";
  Node sim_node("simulator", nodeOptions(Vendor::CYCLONEDDS, 195, params()));
  Node probe_node("probe", nodeOptions(Vendor::CYCLONEDDS, 195));
  SimulatorComponent sim;
  sim.configure(sim_node);
  RangeSensorProbe probe(probe_node);
  interfaces::Executor executor;
  executor.add(sim_node);
  executor.add(probe_node);
  sim.activate();
  // 3 s of simulation: a 10 Hz multibeam would have sent ~30 scans.
  EXPECT_TRUE(executor.spinUntil([&] { return probe.odom >= 30; }, 30s)) << probe.odom;
  sim.deactivate();
  EXPECT_EQ(probe.scans, 0);
  EXPECT_EQ(probe.dvl_pings, 0);
}

TEST_F(SimulatorComponentTest, ABadMultibeamSectionIsRefusedNamingFileAndField) {
  std::ofstream(scenario_, std::ios::app) << "multibeam: {horizontal_aperture_deg: 190}\n";
  Node node("simulator", nodeOptions(Vendor::CYCLONEDDS, 196, params()));
  SimulatorComponent sim;
  try {
    sim.configure(node);
    FAIL() << "accepted a 190 deg fan";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("wall.yaml: multibeam.horizontal_aperture_deg"),
              std::string::npos)
        << e.what();
  }
}

// Live preview frames: the forward camera 2 m from the wall, as JPEG at a quarter of its
// size, across vendors, shows the wall (the same camera 46 m away sees only water); an unknown
// camera is refused naming it.
TEST_F(SimulatorComponentTest, PublishesLiveCameraFramesOfWhatTheCameraSees) {
  const CameraModel forward(CameraOptions::defaults("forward"), 0.25);
  const auto liveFrames = [&](double start_x, int domain) {
    std::ofstream(scenario_) << "name: wall\n"
                                "world: {mesh: wall.ply, seabed_depth: 10}\n"
                                "water: {visibility: 5}\n"
                                "vehicle: {start: {position: ["
                             << start_x << ", 0, 3], yaw_deg: 0}}\n";
    std::vector<std::string> overrides = params();
    overrides.insert(overrides.end(), {"camera_live_rate:=2.0", "camera_live_scale:=0.25",
                                       "camera_live_cameras:=[forward]"});
    Node sim_node("simulator", nodeOptions(Vendor::CYCLONEDDS, domain, overrides));
    Node probe("probe", nodeOptions(Vendor::FASTDDS, domain));
    SimulatorComponent sim;
    sim.configure(sim_node);
    std::vector<msg::CompressedImage> frames;
    auto subscription = probe.createSubscription<msg::CompressedImage>(
        "camera/forward/compressed", interfaces::sensorDataQos(),
        std::function<void(const msg::CompressedImage&)>(
            [&](const msg::CompressedImage& m) { frames.push_back(m); }));
    interfaces::Executor executor;
    executor.add(sim_node);
    executor.add(probe);
    sim.activate();
    EXPECT_TRUE(executor.spinUntil([&] { return frames.size() >= 2; }, 60s));
    sim.deactivate();
    std::vector<cv::Mat> images;
    for (const auto& frame : frames) {
      EXPECT_EQ(frame.format(), "jpeg");
      EXPECT_EQ(frame.header().frame_id(), "camera_forward");
      images.push_back(cv::imdecode(frame.data(), cv::IMREAD_COLOR));
      EXPECT_EQ(images.back().cols, forward.width());
      EXPECT_EQ(images.back().rows, forward.height());
    }
    return images;
  };
  const std::vector<cv::Mat> near = liveFrames(4.0, 197);
  const std::vector<cv::Mat> far = liveFrames(-40.0, 198);
  ASSERT_FALSE(near.empty());
  ASSERT_FALSE(far.empty());
  // The wall fills the near view: its centre differs from open water far more than two frames
  // of open water differ from each other (sensor noise, JPEG).
  ASSERT_GE(far.size(), 2u);
  const cv::Rect centre(forward.width() / 4, forward.height() / 4, forward.width() / 2,
                        forward.height() / 2);
  const auto meanDifference = [&](const cv::Mat& a, const cv::Mat& b) {
    cv::Mat difference;
    cv::absdiff(a(centre), b(centre), difference);
    const cv::Scalar mean = cv::mean(difference);
    return mean[0] + mean[1] + mean[2];
  };
  const double noise = meanDifference(far[0], far[1]);
  EXPECT_GT(meanDifference(near.front(), far.front()), 3 * noise + 3)
      << "the wall is not in the live frame (noise " << noise << ")";

  std::vector<std::string> overrides = params();
  overrides.push_back("camera_live_rate:=1.0");
  overrides.push_back("camera_live_cameras:=[periscope]");
  Node bad_node("simulator_bad", nodeOptions(Vendor::CYCLONEDDS, 199, overrides));
  SimulatorComponent bad;
  try {
    bad.configure(bad_node);
    ADD_FAILURE() << "an unknown camera was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("periscope"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::sim
