// The mapping component on real DDS: the component on Fast DDS fed with odometry and beams at a
// wall; a late-joining map reader on Cyclone DDS gets a FULL map with the wall cell occupied and
// keeps an exact replica from the increments; map/save and map/clear answer across vendors; a
// saved map given as initial_map is the map from the start; DVL beams on dvl/beams (body-frame
// clouds stamped past the newest odometry) wait for it and enter the map as rays; a repeat
// mission's initial_map is published only once the vehicle's returns align with it.
// Each test on its own domain id (80..89, 8, 4).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/mapping/components/mapping_component.h"
#include "auv/mapping/map_replica.h"
#include "synthetic_scene.h"

namespace auv::mapping {
namespace {

using namespace std::chrono_literals;
using interfaces::Node;
using interfaces::NodeOptions;
using interfaces::nodeOptions;
using interfaces::Vendor;

void setStamp(msg::Header& header, int64_t ns) {
  header.stamp().sec(static_cast<int32_t>(ns / 1000000000));
  header.stamp().nanosec(static_cast<uint32_t>(ns % 1000000000));
}

// Wall at x = 8.3 m (cell [8, 8.5)), vehicle parked at (0.1, 0.2, 0.2) heading north (+x).
constexpr double kWallX = 8.3;
const Eigen::Vector3d kVehicle(0.1, 0.2, 0.2);

/// Publishes odometry at each tick and a beam stamped half-way between the last two, sweeping
/// the head over +-0.3 rad with every fourth beam straight ahead.
class Feeder {
 public:
  Feeder(Node& node) : node_(node) {
    odometry_ = node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
    beams_ = node.createPublisher<msg::SonarBeam>("sonar/beam", interfaces::sensorDataQos());
    timer_ = node.createTimer(0.01, [this] { tick(); });
  }
  void stop() { timer_->cancel(); }
  /// From now on the navigation estimate is off by `offset` (a jump); the world stays.
  void jumpNavigation(const Eigen::Vector3d& offset) {
    offset_x_ = offset.x();
    offset_y_ = offset.y();
  }

 private:
  void tick() {
    const int64_t now = node_.clock().nowNs();
    msg::Odometry odometry;
    setStamp(odometry.header(), now);
    odometry.header().frame_id("world");
    odometry.pose().pose().position().x(kVehicle.x() + offset_x_);
    odometry.pose().pose().position().y(kVehicle.y() + offset_y_);
    odometry.pose().pose().position().z(kVehicle.z());
    odometry.pose().pose().orientation().w(1.0);
    odometry_->publish(odometry);
    if (last_odometry_ns_ > 0) {
      msg::SonarBeam beam;
      setStamp(beam.header(), (now + last_odometry_ns_) / 2);
      beam.header().frame_id("sonar");
      beam.mounting().orientation().w(1.0);
      const double angle = (count_ % 4 == 0) ? 0.0 : 0.3 * std::sin(0.1 * count_);
      beam.beam_angle(static_cast<float>(angle));
      beam.min_range(0.5f);
      beam.max_range(20.0f);
      beam.ranges({static_cast<float>((kWallX - kVehicle.x()) / std::cos(angle))});
      beam.flags(msg::SONAR_BEAM_ECHO_RETURNED);
      beams_->publish(beam);
      ++count_;
    }
    last_odometry_ns_ = now;
  }

  Node& node_;
  std::shared_ptr<interfaces::Publisher<msg::Odometry>> odometry_;
  std::shared_ptr<interfaces::Publisher<msg::SonarBeam>> beams_;
  std::shared_ptr<interfaces::Timer> timer_;
  int64_t last_odometry_ns_ = 0;
  int count_ = 0;
  std::atomic<double> offset_x_{0.0}, offset_y_{0.0};
};

/// A map reader like the planner's: FULL replaces, INCREMENTAL applies on an unbroken chain.
struct MapReader {
  std::unique_ptr<octomap::OcTree> tree;
  uint64_t applied_sequence = 0;
  int fulls = 0;
  int increments = 0;
  int dropped = 0;  // increments that did not continue the chain
  bool wall_occupied_in_first_full = false;

  /// The planner's subscription to map/update, feeding onUpdate().
  std::shared_ptr<interfaces::Subscription<msg::OctomapUpdate>> subscribe(Node& node) {
    return node.createSubscription<msg::OctomapUpdate>(
        "map/update", interfaces::mapQos(),
        std::function<void(const msg::OctomapUpdate&)>(
            [this](const msg::OctomapUpdate& u) { onUpdate(u); }));
  }

  void onUpdate(const msg::OctomapUpdate& update) {
    const std::string data(update.data().begin(), update.data().end());
    if (update.kind() == msg::OCTOMAP_UPDATE_FULL) {
      std::istringstream stream(data);
      std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(stream));
      auto* full = dynamic_cast<octomap::OcTree*>(read.get());
      ASSERT_NE(full, nullptr);
      read.release();
      tree.reset(full);
      applied_sequence = update.sequence_number();
      if (fulls++ == 0) {
        const octomap::OcTreeNode* wall = tree->search(8.25, 0.25, 0.25);
        wall_occupied_in_first_full = wall != nullptr && tree->isNodeOccupied(wall);
      }
    } else if (update.kind() == msg::OCTOMAP_UPDATE_INCREMENTAL && tree &&
               update.base_sequence() == applied_sequence) {
      MapBuilder::applyDiff(data, *tree);
      applied_sequence = update.sequence_number();
      ++increments;
    } else {
      ++dropped;
    }
  }
};

TEST(MappingComponentTest, LateJoinerOnOtherVendorGetsFullMapAndExactIncrements) {
  constexpr int kDomain = 80;
  Node mapping_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain,
                                           {"update_rate:=20.0", "full_map_period:=3600.0"}));
  Node feeder_node("feeder", nodeOptions(Vendor::FASTDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  Feeder feeder(feeder_node);
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(feeder_node);
  mapping.activate();
  ASSERT_TRUE(executor.spinUntil([&] { return mapping.beamsInserted() >= 40; }, 20s));
  // Increments have gone out before the reader exists.
  ASSERT_TRUE(executor.spinUntil([&] { return mapping.sequenceNumber() >= 3; }, 20s));

  Node reader_node("planner", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  MapReader reader;
  auto subscription = reader.subscribe(reader_node);
  executor.add(reader_node);
  ASSERT_TRUE(executor.spinUntil([&] { return reader.fulls >= 1 && reader.increments >= 2; }, 20s))
      << "fulls " << reader.fulls << ", increments " << reader.increments << ", dropped "
      << reader.dropped << ", map version " << mapping.sequenceNumber();
  EXPECT_TRUE(reader.wall_occupied_in_first_full);

  // Stop the input and let the last changes reach the reader.
  feeder.stop();
  ASSERT_TRUE(executor.spinUntil(
      [&] {
        return mapping.builder().pendingChangeCount() == 0 &&
               reader.applied_sequence == mapping.sequenceNumber();
      },
      20s));
  const octomap::OcTree& built = mapping.builder().tree();
  ASSERT_NE(reader.tree, nullptr);
  const octomap::OcTreeNode* wall = reader.tree->search(8.25, 0.25, 0.25);
  ASSERT_NE(wall, nullptr);
  EXPECT_TRUE(reader.tree->isNodeOccupied(wall));
  const octomap::OcTreeNode* water = reader.tree->search(4.25, 0.25, 0.25);
  ASSERT_NE(water, nullptr);
  EXPECT_FALSE(reader.tree->isNodeOccupied(water));
  std::size_t compared = 0;
  for (auto it = built.begin_leafs(); it != built.end_leafs(); ++it, ++compared) {
    const octomap::OcTreeNode* copy = reader.tree->search(it.getKey());
    ASSERT_NE(copy, nullptr) << it.getCoordinate();
    EXPECT_EQ(copy->getLogOdds(), it->getLogOdds()) << it.getCoordinate();
  }
  EXPECT_GT(compared, 10u);
  EXPECT_EQ(reader.tree->getNumLeafNodes(), built.getNumLeafNodes());
  // In-process readers see the same map through the snapshot, copied at the next update after
  // they asked (snapshot() asks).
  EXPECT_TRUE(executor.spinUntil(
      [&] { return mapping.builder().snapshot()->getNumLeafNodes() == built.getNumLeafNodes(); },
      5s));
  mapping.deactivate();
}

TEST(MappingComponentTest, SaveWritesLoadableBtAndClearEmptiesTheMap) {
  constexpr int kDomain = 81;
  const std::string directory = testing::TempDir() + "mapping_component_test_maps";
  std::filesystem::remove_all(directory);
  Node mapping_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain,
                                           {"update_rate:=20.0", "map_directory:=" + directory}));
  Node feeder_node("feeder", nodeOptions(Vendor::FASTDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  Feeder feeder(feeder_node);
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(feeder_node);
  mapping.activate();
  ASSERT_TRUE(executor.spinUntil([&] { return mapping.beamsInserted() >= 20; }, 20s));
  feeder.stop();

  Node operator_node("operator", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  auto save = operator_node.createClient<msg::SaveMapRequest, msg::SaveMapReply>("map/save");
  auto clear = operator_node.createClient<msg::TriggerRequest, msg::TriggerReply>("map/clear");
  std::thread spinner([&] { executor.spin(); });
  msg::SaveMapRequest request;
  request.file_path("sub/wall.bt");
  msg::SaveMapReply reply;
  const auto save_status = save->call(request, &reply, 10s);
  msg::SaveMapRequest escape;
  escape.file_path("../outside.bt");
  msg::SaveMapReply refused;
  const auto escape_status = save->call(escape, &refused, 10s);
  msg::TriggerReply cleared;
  const auto clear_status = clear->call(msg::TriggerRequest(), &cleared, 10s);
  executor.shutdown();
  spinner.join();

  ASSERT_EQ(save_status, interfaces::CallStatus::OK);
  ASSERT_EQ(reply.status().code(), msg::REPLY_CODE_OK) << reply.status().error_text();
  EXPECT_EQ(reply.file_path(), "sub/wall.bt");
  EXPECT_EQ(reply.size_bytes(), std::filesystem::file_size(directory + "/sub/wall.bt"));
  octomap::OcTree loaded(0.1);
  ASSERT_TRUE(loaded.readBinary(directory + "/sub/wall.bt"));
  const octomap::OcTreeNode* wall = loaded.search(8.25, 0.25, 0.25);
  ASSERT_NE(wall, nullptr);
  EXPECT_TRUE(loaded.isNodeOccupied(wall));

  ASSERT_EQ(escape_status, interfaces::CallStatus::OK);
  EXPECT_EQ(refused.status().code(), msg::REPLY_CODE_INVALID_ARGUMENT);
  EXPECT_FALSE(std::filesystem::exists(directory + "/../outside.bt"));

  ASSERT_EQ(clear_status, interfaces::CallStatus::OK);
  EXPECT_EQ(cleared.status().code(), msg::REPLY_CODE_OK);
  EXPECT_EQ(mapping.builder().tree().size(), 0u);
  mapping.deactivate();
  std::filesystem::remove_all(directory);
}

// The periodic FULL map repeats the version of the update before it, so a reader that followed
// every increment skips it (no parse, no rebuild of what depends on the map) and still holds
// the mapper's exact map; a clear makes a new version, which the reader does take.
TEST(MappingComponentTest, AReplicaInStepSkipsThePeriodicFullMapButNotAClear) {
  constexpr int kDomain = 84;
  Node mapping_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain,
                                           {"update_rate:=20.0", "full_map_period:=0.3"}));
  Node feeder_node("feeder", nodeOptions(Vendor::FASTDDS, kDomain));
  Node reader_node("planner", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  MapReplica replica("octomap", 0.5);
  int full_applied = 0;
  int full_skipped = 0;
  auto subscription = reader_node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>([&](const msg::OctomapUpdate& u) {
        const MapReplica::Outcome outcome = replica.apply(u);
        if (u.kind() != msg::OCTOMAP_UPDATE_FULL) return;
        full_applied += outcome == MapReplica::Outcome::APPLIED;
        full_skipped += outcome == MapReplica::Outcome::UNCHANGED;
      }));
  Feeder feeder(feeder_node);
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(feeder_node);
  executor.add(reader_node);
  mapping.activate();
  // Beams keep changing the map meanwhile: each FULL follows an increment of its changes.
  ASSERT_TRUE(executor.spinUntil([&] { return full_skipped >= 3; }, 20s))
      << "FULL maps applied " << full_applied << ", skipped " << full_skipped;
  feeder.stop();
  ASSERT_TRUE(executor.spinUntil(
      [&] {
        return mapping.builder().pendingChangeCount() == 0 &&
               replica.sequence() == mapping.sequenceNumber();
      },
      20s));
  EXPECT_LE(full_applied, 2) << "the first FULL, and one more if it crossed the first increments";
  const octomap::OcTree& built = mapping.builder().tree();
  ASSERT_GT(built.getNumLeafNodes(), 10u);
  EXPECT_EQ(replica.tree().getNumLeafNodes(), built.getNumLeafNodes());
  for (auto it = built.begin_leafs(); it != built.end_leafs(); ++it) {
    const octomap::OcTreeNode* copy = replica.tree().search(it.getKey());
    ASSERT_NE(copy, nullptr) << it.getCoordinate();
    EXPECT_EQ(copy->getLogOdds(), it->getLogOdds()) << it.getCoordinate();
  }

  auto clear = reader_node.createClient<msg::TriggerRequest, msg::TriggerReply>("map/clear");
  const int applied_before_clear = full_applied;
  std::atomic<bool> called{false};
  interfaces::CallStatus clear_status = interfaces::CallStatus::TIMEOUT;
  std::thread caller([&] {  // the call blocks; this thread keeps spinning the components
    msg::TriggerReply cleared;
    clear_status = clear->call(msg::TriggerRequest(), &cleared, 10s);
    called = true;
  });
  const bool cleared = executor.spinUntil(
      [&] { return called && full_applied > applied_before_clear && replica.tree().size() == 0; },
      15s);
  caller.join();
  ASSERT_EQ(clear_status, interfaces::CallStatus::OK);
  EXPECT_TRUE(cleared) << "the cleared map was skipped: the replica still holds "
                       << replica.tree().getNumLeafNodes() << " leaves";
  EXPECT_EQ(replica.sequence(), mapping.sequenceNumber());
  mapping.deactivate();
}

// initial_map with align_initial_map false: a map saved earlier is the map from the start, and
// the first FULL gives it to a reader of the other vendor before any sonar data; a file it
// cannot take is refused naming the parameter and the file.
TEST(MappingComponentTest, StartsFromAnInitialMapAndNamesOneItCannotTake) {
  constexpr int kDomain = 85;
  const std::string path = testing::TempDir() + "mapping_component_initial.bt";
  MapBuilder earlier;
  const std::vector<Eigen::Vector3d> wall = {{8.25, 0.25, 0.25}, {8.25, 0.75, 0.25}};
  earlier.insertCloud(wall, Eigen::Vector3d(0.25, 0.25, 0.25), 0.0);
  ASSERT_TRUE(earlier.save(path));

  // A map in this run's frame, trusted as it is (the alignment has its own test below).
  Node mapping_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain,
                                           {"initial_map:=" + path, "align_initial_map:=false"}));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  EXPECT_EQ(mapping.builder().fullBinary(), earlier.fullBinary());
  Node reader_node("planner", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  MapReader reader;
  auto subscription = reader.subscribe(reader_node);
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(reader_node);
  mapping.activate();
  ASSERT_TRUE(executor.spinUntil([&] { return reader.fulls >= 1; }, 20s));
  EXPECT_TRUE(reader.wall_occupied_in_first_full);
  EXPECT_EQ(mapping.beamsInserted(), 0u);
  mapping.deactivate();
  std::remove(path.c_str());

  const std::string missing = testing::TempDir() + "no_such_initial_map.bt";
  Node refused_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain, {"initial_map:=" + missing}));
  MappingComponent refused;
  try {
    refused.configure(refused_node);
    ADD_FAILURE() << "a missing initial_map was accepted";
  } catch (const interfaces::ParameterError& error) {
    EXPECT_NE(std::string(error.what()).find("initial_map"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos) << error.what();
  }
}

// The simulator's dvl/beams: four bottom returns in the body frame ("base_link"), the rays'
// origin in sensor_origin, stamped a little after the odometry published with them, so that
// each must wait for the next odometry sample to be placed.
TEST(MappingComponentTest, DvlBeamCloudsWaitForOdometryAndEnterTheMapAsRays) {
  constexpr int kDomain = 8;         // 80..89 are taken (test/README.md)
  constexpr double kAltitude = 4.0;  // seabed 4 m below the DVL head
  const Eigen::Vector3d head(0.0, 0.0, 0.2);
  Node mapping_node("mapping", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  Node feeder_node("dvl", nodeOptions(Vendor::FASTDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  auto odometry =
      feeder_node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  auto beams =
      feeder_node.createPublisher<msg::PointCloud>("dvl/beams", interfaces::sensorDataQos());
  std::vector<Eigen::Vector3d> footprints;  // body frame
  for (int k = 0; k < 4; ++k) {
    const double azimuth = M_PI / 4 + k * M_PI / 2, tilt = M_PI / 6;
    footprints.push_back(head + kAltitude / std::cos(tilt) *
                                    Eigen::Vector3d(std::sin(tilt) * std::cos(azimuth),
                                                    std::sin(tilt) * std::sin(azimuth),
                                                    std::cos(tilt)));
  }
  auto timer = feeder_node.createTimer(0.02, [&] {
    const int64_t now = feeder_node.clock().nowNs();
    msg::Odometry o;
    setStamp(o.header(), now);
    o.header().frame_id("world");
    o.pose().pose().position().x(kVehicle.x());
    o.pose().pose().position().y(kVehicle.y());
    o.pose().pose().position().z(kVehicle.z());
    o.pose().pose().orientation().w(1.0);
    odometry->publish(o);
    msg::PointCloud cloud;
    setStamp(cloud.header(), now + 5000000);  // 5 ms after the newest odometry
    cloud.header().frame_id("base_link");
    cloud.sensor_origin().position().z(head.z());
    cloud.sensor_origin().orientation().w(1.0);
    cloud.max_range(60.0f);
    for (const Eigen::Vector3d& f : footprints) {
      msg::PointXYZI p;
      p.x(static_cast<float>(f.x()));
      p.y(static_cast<float>(f.y()));
      p.z(static_cast<float>(f.z()));
      p.intensity(0.87f);
      cloud.points().push_back(p);
    }
    beams->publish(cloud);
  });
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(feeder_node);
  mapping.activate();
  ASSERT_TRUE(executor.spinUntil([&] { return mapping.cloudsInserted() >= 10; }, 20s))
      << "inserted " << mapping.cloudsInserted() << " dropped " << mapping.cloudsDropped();
  timer->cancel();
  mapping.deactivate();
  const octomap::OcTree& tree = mapping.builder().tree();
  for (const Eigen::Vector3d& f : footprints) {
    const Eigen::Vector3d bottom = kVehicle + f;
    const octomap::OcTreeNode* cell = tree.search(bottom.x(), bottom.y(), bottom.z());
    ASSERT_NE(cell, nullptr) << bottom.transpose();
    EXPECT_TRUE(tree.isNodeOccupied(cell)) << bottom.transpose();
    const Eigen::Vector3d water = kVehicle + head + 0.5 * (f - head);  // half-way along the ray
    const octomap::OcTreeNode* free = tree.search(water.x(), water.y(), water.z());
    ASSERT_NE(free, nullptr) << water.transpose();
    EXPECT_FALSE(tree.isNodeOccupied(free)) << water.transpose();
  }
}

// initial_map of a repeat mission (align_initial_map, the default): the first visit's map of a
// canyon, the vehicle now in a navigation frame offset by (2.5 m, -1.5 m, yaw 4 deg) sending
// body-frame sonar/scan fans with its odometry. Until the returns align, the published map holds
// only them; then the FULL after alignment holds the prior's walls at the shifted place (also
// where the vehicle has not been), and prior_alignment.json records the transform.
TEST(MappingComponentTest, ARepeatMissionAlignsThePriorMapBeforePublishingIt) {
  constexpr int kDomain = 4;  // 80..89 and 8 are taken (test/README.md); 4 is unused
  const test::Scene canyon = test::canyonScene();
  const std::string directory = testing::TempDir() + "mapping_component_prior";
  std::filesystem::remove_all(directory);
  std::filesystem::create_directories(directory);
  const std::string path = directory + "/first_visit.bt";
  MapBuilder first_visit;
  test::mapVisit(first_visit, canyon, -24.0, 26.0);
  ASSERT_TRUE(first_visit.save(path));

  Eigen::Isometry3d navigation_T_world = Eigen::Isometry3d::Identity();
  navigation_T_world.linear() =
      Eigen::AngleAxisd(4.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  navigation_T_world.translation() = Eigen::Vector3d(2.5, -1.5, 0.0);

  Node mapping_node("mapping", nodeOptions(Vendor::CYCLONEDDS, kDomain,
                                           {"initial_map:=" + path, "map_directory:=" + directory,
                                            "update_rate:=20.0", "prior_min_points:=1200",
                                            "prior_retry_points:=400"}));
  Node vehicle_node("vehicle", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  Node reader_node("planner", nodeOptions(Vendor::FASTDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  ASSERT_NE(mapping.priorAlignment(), nullptr);
  EXPECT_EQ(mapping.priorAlignment()->state, AlignmentState::COLLECTING);
  EXPECT_EQ(mapping.builder().tree().size(), 0u) << "the prior is held aside";

  std::unique_ptr<octomap::OcTree> last_full;
  uint64_t last_full_sequence = 0;
  auto subscription = reader_node.createSubscription<msg::OctomapUpdate>(
      "map/update", interfaces::mapQos(),
      std::function<void(const msg::OctomapUpdate&)>([&](const msg::OctomapUpdate& u) {
        if (u.kind() != msg::OCTOMAP_UPDATE_FULL) return;
        std::istringstream stream(std::string(u.data().begin(), u.data().end()));
        last_full.reset(dynamic_cast<octomap::OcTree*>(octomap::AbstractOcTree::read(stream)));
        last_full_sequence = u.sequence_number();
      }));

  // The vehicle (true heading +x, the body frame's axes those of the world) drives along the
  // canyon at y = 1, z = 2.5; its navigation believes position T * p and yaw 4 deg.
  auto odometry =
      vehicle_node.createPublisher<msg::Odometry>("nav/odometry", interfaces::stateQos());
  auto scans =
      vehicle_node.createPublisher<msg::PointCloud>("sonar/scan", interfaces::sensorDataQos());
  double x = -15.0;
  auto timer = vehicle_node.createTimer(0.05, [&] {
    const int64_t now = vehicle_node.clock().nowNs();
    const Eigen::Vector3d origin(x, 1.0, 2.5);
    msg::Odometry o;
    setStamp(o.header(), now);
    o.header().frame_id("world");
    const Eigen::Vector3d believed = navigation_T_world * origin;
    const Eigen::Quaterniond attitude(navigation_T_world.linear());
    o.pose().pose().position().x(believed.x());
    o.pose().pose().position().y(believed.y());
    o.pose().pose().position().z(believed.z());
    o.pose().pose().orientation().w(attitude.w());
    o.pose().pose().orientation().x(attitude.x());
    o.pose().pose().orientation().y(attitude.y());
    o.pose().pose().orientation().z(attitude.z());
    odometry->publish(o);
    msg::PointCloud cloud;
    setStamp(cloud.header(), now);
    cloud.header().frame_id("base_link");
    cloud.sensor_origin().orientation().w(1.0);
    cloud.max_range(20.0f);
    for (const Eigen::Vector3d& point : test::castFan(canyon, origin).points) {
      msg::PointXYZI p;
      p.x(static_cast<float>(point.x() - origin.x()));
      p.y(static_cast<float>(point.y() - origin.y()));
      p.z(static_cast<float>(point.z() - origin.z()));
      cloud.points().push_back(p);
    }
    scans->publish(cloud);
    x = std::min(x + 0.25, 12.0);
  });

  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(vehicle_node);
  executor.add(reader_node);
  mapping.activate();
  // Where the prior has the canyon's wall at x = 20 (the vehicle stays short of it).
  const double wall_y = 7.0 + 0.8 * std::sin(2.0 * M_PI * 20.0 / 13.0);
  const Eigen::Vector3d far_wall = navigation_T_world * Eigen::Vector3d(20.0, wall_y, 4.0);
  const auto occupiedNear = [](const octomap::OcTree& map, const Eigen::Vector3d& p) {
    for (double dx = -0.5; dx <= 0.5; dx += 0.5) {
      for (double dy = -0.5; dy <= 0.5; dy += 0.5) {
        for (double dz = -0.5; dz <= 0.5; dz += 0.5) {
          const octomap::OcTreeNode* cell = map.search(p.x() + dx, p.y() + dy, p.z() + dz);
          if (cell != nullptr && map.isNodeOccupied(cell)) return true;
        }
      }
    }
    return false;
  };
  bool prior_before_alignment = false;
  uint64_t aligned_sequence = 0;
  ASSERT_TRUE(executor.spinUntil(
      [&] {
        const AlignmentResult& r = *mapping.priorAlignment();
        if (r.state != AlignmentState::ALIGNED) {
          prior_before_alignment |= occupiedNear(mapping.builder().tree(), far_wall);
          return r.finished;
        }
        if (aligned_sequence == 0) aligned_sequence = mapping.sequenceNumber();
        return true;
      },
      60s))
      << mapping.priorAlignment()->reason;
  const AlignmentResult result = *mapping.priorAlignment();
  ASSERT_EQ(result.state, AlignmentState::ALIGNED) << result.reason;
  EXPECT_FALSE(prior_before_alignment) << "the map had prior content before the alignment";
  EXPECT_GT(mapping.cloudsInserted(), 0u);
  EXPECT_NEAR(result.x_m, 2.5, 0.15);
  EXPECT_NEAR(result.y_m, -1.5, 0.15);
  EXPECT_NEAR(result.yaw_rad * 180.0 / M_PI, 4.0, 0.5);

  ASSERT_TRUE(
      executor.spinUntil([&] { return last_full && last_full_sequence >= aligned_sequence; }, 20s))
      << "no FULL map after the alignment (sequence " << aligned_sequence << ")";
  timer->cancel();
  mapping.deactivate();
  EXPECT_TRUE(occupiedNear(*last_full, far_wall)) << "the prior's wall at the shifted place";
  // The top of the prior's boulder at x = 21 where the moved prior puts it, not where it was.
  const Eigen::Vector3d boulder_top(21.0, 1.4, 5.2);
  EXPECT_TRUE(occupiedNear(*last_full, navigation_T_world * boulder_top));
  EXPECT_FALSE(occupiedNear(*last_full, boulder_top)) << "the prior unmoved";

  std::ifstream record(directory + "/prior_alignment.json");
  ASSERT_TRUE(record) << "no prior_alignment.json in " << directory;
  const std::string json((std::istreambuf_iterator<char>(record)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"state\": \"ALIGNED\""), std::string::npos) << json;
  const std::size_t x_at = json.find("\"x\": ");
  ASSERT_NE(x_at, std::string::npos) << json;
  EXPECT_NEAR(std::stod(json.substr(x_at + 5)), result.x_m, 1e-6) << json;
  std::filesystem::remove_all(directory);
}

// A reset of the navigation estimate by 3 m: the wall seen before and after it must stay one
// wall, at its place in the new frame, in the map and in a reader's replica (a FULL follows).
TEST(MappingComponentTest, ANavigationJumpMovesTheMapWithTheEstimate) {
  constexpr int kDomain = 34;  // free inside the interop range (test/README.md)
  Node mapping_node("mapping", nodeOptions(Vendor::FASTDDS, kDomain, {"update_rate:=20.0"}));
  Node feeder_node("feeder", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  Node reader_node("reader", nodeOptions(Vendor::CYCLONEDDS, kDomain));
  MappingComponent mapping;
  mapping.configure(mapping_node);
  Feeder feeder(feeder_node);
  MapReader reader;
  auto subscription = reader.subscribe(reader_node);
  interfaces::Executor executor;
  executor.add(mapping_node);
  executor.add(feeder_node);
  executor.add(reader_node);
  mapping.activate();
  const auto occupied = [](const octomap::OcTree& tree, double x, double y) {
    const octomap::OcTreeNode* cell = tree.search(x, y, 0.25);
    return cell != nullptr && tree.isNodeOccupied(cell);
  };
  ASSERT_TRUE(executor.spinUntil([&] { return mapping.beamsInserted() >= 40; }, 20s));
  ASSERT_TRUE(occupied(mapping.builder().tree(), 8.25, 0.25));

  feeder.jumpNavigation({0.0, 3.0, 0.0});
  const uint64_t beams_at_jump = mapping.beamsInserted();
  ASSERT_TRUE(executor.spinUntil(
      [&] {
        return mapping.navigationJumps() == 1 && mapping.beamsInserted() >= beams_at_jump + 40 &&
               reader.tree && occupied(*reader.tree, 8.25, 3.25);
      },
      20s));
  feeder.stop();
  const octomap::OcTree& map = mapping.builder().tree();
  // The wall is where the new estimate sees it, and nowhere else: no ghost at its old place.
  EXPECT_TRUE(occupied(map, 8.25, 3.25));
  EXPECT_FALSE(occupied(map, 8.25, 0.25));
  EXPECT_FALSE(occupied(*reader.tree, 8.25, 0.25));
  EXPECT_EQ(mapping.navigationJumps(), 1u);
  mapping.deactivate();
}

TEST(MappingComponentTest, InconsistentProbabilitiesAreRefused) {
  Node node("mapping",
            nodeOptions(Vendor::CYCLONEDDS, 82, {"prob_miss:=0.3", "clamping_min:=0.35"}));
  MappingComponent mapping;
  EXPECT_THROW(mapping.configure(node), std::invalid_argument);
}

TEST(MappingComponentTest, RegisteredAsMapping) {
  EXPECT_NE(interfaces::ComponentRegistry::instance().find("mapping"), nullptr);
}

}  // namespace
}  // namespace auv::mapping
