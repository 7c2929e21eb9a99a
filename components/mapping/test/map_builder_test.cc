// MapBuilder against analytic expectations: a beam at a wall at known range, a no-return beam,
// exact replication through incremental diffs, .bt round trip and snapshots; the .ot writer
// against OctoMap's; a MapReplica's choice of which FULL maps to read.
#include "auv/mapping/map_builder.h"
#include "auv/mapping/map_replica.h"
#include "auv/mapping/ot_stream.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <tuple>

namespace auv::mapping {
namespace {

// Cell centres are at multiples of the resolution plus half: keep test points well inside cells.
constexpr double kResolution = 0.5;

bool isOccupied(const octomap::OcTree& tree, double x, double y, double z) {
  const octomap::OcTreeNode* node = tree.search(x, y, z);
  return node != nullptr && tree.isNodeOccupied(node);
}
bool isFree(const octomap::OcTree& tree, double x, double y, double z) {
  const octomap::OcTreeNode* node = tree.search(x, y, z);
  return node != nullptr && !tree.isNodeOccupied(node);
}
bool isUnknown(const octomap::OcTree& tree, double x, double y, double z) {
  return tree.search(x, y, z) == nullptr;
}

Eigen::Isometry3d sensorAt(const Eigen::Vector3d& position, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = position;
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

TEST(MapBuilderTest, BeamAtWallMarksReturnOccupiedAndCellsBeforeFree) {
  MapBuilder builder;
  BeamGeometry beam;
  beam.direction = beamDirection(0.0);
  beam.min_range = 0.0;
  beam.max_range = 20.0;
  beam.return_range = 8.2;  // wall at x = 0.1 + 8.2 = 8.3 -> cell [8, 8.5)
  const InsertStats stats = builder.insertBeam(beam, sensorAt({0.1, 0.2, 0.2}, 0.0));
  EXPECT_EQ(stats.occupied_cells, 1u);
  EXPECT_EQ(stats.free_cells, 16u);  // cells [0, 0.5) .. [7.5, 8)
  const auto& tree = builder.tree();
  EXPECT_TRUE(isOccupied(tree, 8.25, 0.25, 0.25));
  for (double x = 0.25; x < 8.0; x += kResolution) {
    EXPECT_TRUE(isFree(tree, x, 0.25, 0.25)) << "x = " << x;
  }
  EXPECT_TRUE(isUnknown(tree, 8.75, 0.25, 0.25));  // behind the wall: not seen
  EXPECT_TRUE(isUnknown(tree, 4.25, 0.75, 0.25));  // beside the beam
}

TEST(MapBuilderTest, BeamDirectionFollowsSensorPoseAndHeadAngle) {
  MapBuilder builder;
  BeamGeometry beam;
  beam.direction = beamDirection(M_PI / 2);  // head turned to the sensor's y axis
  beam.return_range = 5.0;
  // Sensor yawed +90 deg: its y axis points along world -x.
  builder.insertBeam(beam, sensorAt({10.1, 0.2, 0.2}, M_PI / 2));
  EXPECT_TRUE(isOccupied(builder.tree(), 5.25, 0.25, 0.25));
  EXPECT_TRUE(isFree(builder.tree(), 7.25, 0.25, 0.25));
}

TEST(MapBuilderTest, NoReturnBeamMarksOnlyFreeCellsUpToMaxRange) {
  MapBuilder builder;
  BeamGeometry beam;
  beam.direction = beamDirection(0.0);
  beam.min_range = 1.0;
  beam.max_range = 6.1;  // ends in cell [6, 6.5) at x = 6.2
  const InsertStats stats = builder.insertBeam(beam, sensorAt({0.1, 0.2, 0.2}, 0.0));
  EXPECT_EQ(stats.occupied_cells, 0u);
  EXPECT_GT(stats.free_cells, 0u);
  const auto& tree = builder.tree();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    EXPECT_FALSE(tree.isNodeOccupied(*it)) << it.getCoordinate();
  }
  EXPECT_TRUE(isUnknown(tree, 0.25, 0.25, 0.25));  // inside the blanking distance
  EXPECT_TRUE(isFree(tree, 1.25, 0.25, 0.25));
  EXPECT_TRUE(isFree(tree, 5.75, 0.25, 0.25));
  EXPECT_TRUE(isUnknown(tree, 6.75, 0.25, 0.25));  // beyond max range
}

// A wall along the plane y = 2.2 (cells y in [2, 2.5)), seen by perpendicular echoes from a
// vehicle at y = 0.2, then by silent beams grazing it at 2..10 deg (an echo too weak to
// detect). With the single-ray model each silent beam crosses many wall cells; stopping at the
// first occupied one keeps the wall, and the space behind it stays unseen.
std::size_t wallCellsLeft(bool stop_at_occupied, std::size_t* cells_behind_seen) {
  MapBuilder::Options options;
  options.no_return_stops_at_occupied = stop_at_occupied;
  MapBuilder builder(options);
  BeamGeometry perpendicular;
  perpendicular.return_range = 2.0;
  for (double x = 0.25; x < 20.0; x += kResolution) {
    builder.insertBeam(perpendicular, sensorAt({x, 0.2, 0.2}, M_PI / 2));
  }
  BeamGeometry silent;
  silent.max_range = 20.0;
  for (double deg = 2.0; deg <= 10.0; deg += 0.5) {
    builder.insertBeam(silent, sensorAt({0.1, 0.2, 0.2}, deg * M_PI / 180.0));
  }
  std::size_t left = 0;
  *cells_behind_seen = 0;
  for (double x = 0.25; x < 20.0; x += kResolution) {
    if (isOccupied(builder.tree(), x, 2.25, 0.25)) ++left;
    if (!isUnknown(builder.tree(), x, 2.75, 0.25)) ++*cells_behind_seen;
  }
  return left;
}

TEST(MapBuilderTest, SilentGrazingBeamsStopAtTheWallInsteadOfErasingIt) {
  std::size_t behind = 0;
  EXPECT_EQ(wallCellsLeft(true, &behind), 40u);
  EXPECT_EQ(behind, 0u);
  const std::size_t left_without_rule = wallCellsLeft(false, &behind);
  EXPECT_LT(left_without_rule, 30u) << "the single-ray model should erode the wall";
  EXPECT_GT(behind, 0u);
}

// Beams with an echo from beyond an occupied cell (a copy of a wall left by navigation drift)
// still clear it; silent beams fade an isolated cell (a false return) one miss at a time.
TEST(MapBuilderTest, EchoesClearThroughOccupiedCellsAndSilentBeamsFadeFalseReturns) {
  for (const bool echo : {true, false}) {
    MapBuilder builder;
    BeamGeometry false_return;
    false_return.return_range = 4.2;  // from x = 0.1: the cell [4, 4.5)
    builder.insertBeam(false_return, sensorAt({0.1, 0.2, 0.2}, 0.0));
    ASSERT_TRUE(isOccupied(builder.tree(), 4.25, 0.25, 0.25));
    BeamGeometry later;
    if (echo) later.return_range = 8.2;
    for (int i = 0; i < 20; ++i) builder.insertBeam(later, sensorAt({0.1, 0.2, 0.2}, 0.0));
    EXPECT_TRUE(isFree(builder.tree(), 4.25, 0.25, 0.25)) << (echo ? "echo" : "silent");
  }
}

TEST(MapBuilderTest, CloudMatchesRawInsertPointCloud) {
  MapBuilder builder;
  octomap::OcTree raw(kResolution);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-15.0, 15.0);
  std::vector<Eigen::Vector3d> points;
  octomap::Pointcloud cloud;
  for (int i = 0; i < 300; ++i) {
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random) / 5);
    cloud.push_back(points.back().x(), points.back().y(), points.back().z());
  }
  const Eigen::Vector3d origin(0.3, -0.2, 1.1);
  builder.insertCloud(points, origin, 12.0);
  raw.insertPointCloud(cloud, octomap::point3d(0.3f, -0.2f, 1.1f), 12.0);
  std::ostringstream ours, theirs;
  builder.tree().writeBinaryConst(ours);
  raw.writeBinaryConst(theirs);
  EXPECT_EQ(builder.tree().size(), raw.size());
  EXPECT_EQ(ours.str(), theirs.str());
}

// Beams inserted with lazy updates and settled inner nodes give the tree OctoMap's eager
// updateNode gives, cell by cell in ray order: same log-odds in every node, inner nodes and
// pruning included (.ot bytes). Beams cross, repeat until cells clamp and prune, and some
// have no return.
TEST(MapBuilderTest, BeamsGiveTheTreeOfEagerPerCellUpdates) {
  MapBuilder::Options options;
  options.no_return_stops_at_occupied = false;  // the plain ray rule, as the reference below
  MapBuilder builder(options);
  octomap::OcTree raw(kResolution);
  raw.setProbHit(options.prob_hit);
  raw.setProbMiss(options.prob_miss);
  raw.setClampingThresMin(options.clamping_min);
  raw.setClampingThresMax(options.clamping_max);
  raw.setOccupancyThres(options.occupancy_threshold);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  octomap::KeyRay ray;
  for (int i = 0; i < 3000; ++i) {
    // A vehicle hovering over 2 m past a wall 6-9 m away, beams fanning in yaw and pitch: the
    // cells near it are crossed often enough to clamp and prune; a third see nothing.
    const Eigen::Vector3d origin(0.1 * (i % 20), 0.5 * unit(random), unit(random) - 0.5);
    const double yaw = 1.2 + 0.8 * unit(random);
    BeamGeometry beam;
    beam.direction = Eigen::Vector3d(1.0, 0.0, 0.6 * unit(random) - 0.3).normalized();
    beam.max_range = 12.0;
    if (unit(random) > 0.33) beam.return_range = 6.0 + 3.0 * unit(random);
    builder.insertBeam(beam, sensorAt(origin, yaw));
    const Eigen::Vector3d direction =
        (sensorAt(origin, yaw).linear() * beam.direction).normalized();
    const Eigen::Vector3d end = origin + beam.return_range.value_or(beam.max_range) * direction;
    const octomap::point3d o(origin.x(), origin.y(), origin.z()), e(end.x(), end.y(), end.z());
    ASSERT_TRUE(raw.computeRayKeys(o, e, ray));
    for (const auto& key : ray) raw.updateNode(key, false);
    if (beam.return_range) raw.updateNode(e, true);
  }
  std::ostringstream ours, theirs;
  builder.tree().write(ours);
  raw.write(theirs);
  EXPECT_EQ(builder.tree().size(), raw.size());
  EXPECT_TRUE(ours.str() == theirs.str()) << "the .ot streams differ";  // not dumped: 60 kB
}

// Every finest cell of `a` has the same log-odds in `b`, and both know the same volume.
void expectSameLogOdds(const octomap::OcTree& a, const octomap::OcTree& b) {
  double known_volume = 0.0;
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    const octomap::OcTreeNode* other = b.search(it.getKey());
    ASSERT_NE(other, nullptr) << it.getCoordinate();
    EXPECT_EQ(other->getLogOdds(), it->getLogOdds()) << it.getCoordinate();
    known_volume += std::pow(it.getSize(), 3);
  }
  double other_volume = 0.0;
  for (auto it = b.begin_leafs(); it != b.end_leafs(); ++it)
    other_volume += std::pow(it.getSize(), 3);
  EXPECT_DOUBLE_EQ(known_volume, other_volume);
}

TEST(MapBuilderTest, IncrementalDiffsReproduceTheMapExactly) {
  MapBuilder builder;
  builder.enableChangeTracking(true);
  octomap::OcTree replica(kResolution);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::uniform_real_distribution<double> range(2.0, 25.0);
  std::size_t diffs = 0;
  for (int round = 0; round < 20; ++round) {
    for (int i = 0; i < 60; ++i) {
      BeamGeometry beam;
      beam.direction = beamDirection(angle(random));
      beam.min_range = 0.5;
      beam.max_range = 20.0;
      const double r = range(random);
      if (r <= 20.0) beam.return_range = r;
      builder.insertBeam(beam, sensorAt({0.1 * round, 0.05 * i, 0.3}, 0.01 * round));
    }
    const MapBuilder::Diff diff = builder.takeDiff();
    EXPECT_GT(diff.cell_count, 0u);
    EXPECT_LE(diff.changed_min.x(), diff.changed_max.x());
    EXPECT_EQ(builder.pendingChangeCount(), 0u);
    MapBuilder::applyDiff(diff.data, replica);
    ++diffs;
    // Later diffs carry only what changed, not the map.
    if (round > 0) EXPECT_LT(diff.cell_count, builder.tree().getNumLeafNodes());
  }
  EXPECT_EQ(diffs, 20u);
  expectSameLogOdds(builder.tree(), replica);
  expectSameLogOdds(replica, builder.tree());
  std::ostringstream ours, theirs;
  builder.tree().writeBinaryConst(ours);
  replica.writeBinaryConst(theirs);
  EXPECT_EQ(ours.str(), theirs.str());
}

msg::OctomapUpdate fullUpdate(const MapBuilder& builder, uint64_t sequence, int32_t stamp_s) {
  msg::OctomapUpdate update;
  update.map_id("octomap");
  update.resolution(kResolution);
  update.kind(msg::OCTOMAP_UPDATE_FULL);
  update.encoding(msg::OCTOMAP_ENCODING_FULL);
  update.sequence_number(sequence);
  update.header().stamp().sec(stamp_s);
  const std::string data = builder.fullWithProbabilities();
  update.data(std::vector<uint8_t>(data.begin(), data.end()));
  return update;
}

TEST(MapReplicaTest, SkipsOnlyTheFullMapOfTheVersionItHolds) {
  MapBuilder builder;
  BeamGeometry beam;
  beam.direction = beamDirection(0.0);
  beam.max_range = 20.0;
  beam.return_range = 8.2;
  builder.insertBeam(beam, sensorAt({0.1, 0.2, 0.3}, 0.0));
  MapReplica replica("octomap", kResolution);
  EXPECT_EQ(replica.apply(fullUpdate(builder, 1, 5)), MapReplica::Outcome::APPLIED);
  const octomap::OcTree* held = &replica.tree();
  EXPECT_EQ(replica.apply(fullUpdate(builder, 1, 5)), MapReplica::Outcome::UNCHANGED);
  EXPECT_EQ(&replica.tree(), held) << "the tree held must stay, not be read again";
  // Same number, other stamp: a restarted mapper's version 1, not ours.
  EXPECT_EQ(replica.apply(fullUpdate(builder, 1, 6)), MapReplica::Outcome::APPLIED);
  // After a lost increment even the version held is read again: the copy may be off.
  msg::OctomapUpdate increment = fullUpdate(builder, 3, 7);
  increment.kind(msg::OCTOMAP_UPDATE_INCREMENTAL);
  increment.base_sequence(2);
  EXPECT_EQ(replica.apply(increment), MapReplica::Outcome::GAP);
  EXPECT_EQ(replica.apply(fullUpdate(builder, 1, 6)), MapReplica::Outcome::APPLIED);
  EXPECT_FALSE(replica.needsFullMap());
  EXPECT_TRUE(isOccupied(replica.tree(), 8.25, 0.25, 0.25));
}

TEST(MapBuilderTest, ApplyDiffExpandsCoarseLeaves) {
  // A diff whose eight sibling cells share a value is pruned to one leaf one level up.
  octomap::OcTree changes(kResolution);
  for (double x : {0.25, 0.75})
    for (double y : {0.25, 0.75})
      for (double z : {0.25, 0.75}) changes.updateNode(x, y, z, true);
  changes.prune();
  ASSERT_EQ(changes.getNumLeafNodes(), 1u);
  std::ostringstream stream;
  changes.write(stream);
  octomap::OcTree replica(kResolution);
  MapBuilder::applyDiff(stream.str(), replica);
  expectSameLogOdds(changes, replica);
  EXPECT_TRUE(isOccupied(replica, 0.75, 0.25, 0.75));
}

TEST(MapBuilderTest, ApplyDiffRejectsOtherResolutionAndGarbage) {
  MapBuilder builder;
  builder.enableChangeTracking(true);
  BeamGeometry beam;
  beam.return_range = 3.0;
  builder.insertBeam(beam, sensorAt({0, 0, 0}, 0));
  const std::string data = builder.takeDiff().data;
  octomap::OcTree fine(0.1);
  EXPECT_THROW(MapBuilder::applyDiff(data, fine), std::runtime_error);
  EXPECT_THROW(MapBuilder::applyDiff("not a tree", fine), std::runtime_error);
  // A diff whose root is a leaf stands for 2^48 cells: refused before anything is set.
  const std::string root_leaf =
      "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.5\ndata\n" + std::string("\0\0\0\0\0", 5);
  octomap::OcTree replica(0.5);
  EXPECT_THROW(MapBuilder::applyDiff(root_leaf, replica), std::runtime_error);
  EXPECT_EQ(replica.size(), 0u);
}

// A ring of returns 7-10.5 m around the origin, one beam every 10 degrees.
void insertRingOfReturns(MapBuilder& builder) {
  BeamGeometry beam;
  for (int i = 0; i < 36; ++i) {
    beam.direction = beamDirection(i * M_PI / 18);
    beam.return_range = 7.0 + 0.1 * i;
    builder.insertBeam(beam, sensorAt({0.1, 0.1, 0.1}, 0));
  }
}

TEST(MapBuilderTest, SavedBtLoadsBackWithTheSameOccupancy) {
  MapBuilder builder;
  insertRingOfReturns(builder);
  const std::string path = testing::TempDir() + "map_builder_test.bt";
  ASSERT_TRUE(builder.save(path));
  octomap::OcTree loaded(0.1);
  ASSERT_TRUE(loaded.readBinary(path));
  EXPECT_DOUBLE_EQ(loaded.getResolution(), kResolution);
  std::size_t occupied = 0;
  for (auto it = builder.tree().begin_leafs(); it != builder.tree().end_leafs(); ++it) {
    const octomap::OcTreeNode* node = loaded.search(it.getKey());
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(loaded.isNodeOccupied(node), builder.tree().isNodeOccupied(*it));
    occupied += builder.tree().isNodeOccupied(*it);
  }
  EXPECT_GT(occupied, 10u);
  // The in-memory stream equals the file.
  std::ostringstream copy;
  loaded.writeBinaryConst(copy);
  EXPECT_EQ(copy.str(), builder.fullBinary());
  EXPECT_FALSE(builder.save("/nonexistent-dir/x.bt"));
  std::remove(path.c_str());
}

// A checkpoint (.ot) gives the map back with every cell's log-odds, not only occupied / free;
// a damaged one is refused naming the file and leaves the map as it was.
TEST(MapBuilderTest, LoadOfACheckpointKeepsEveryCellsLogOdds) {
  MapBuilder earlier;
  insertRingOfReturns(earlier);
  const std::string path = testing::TempDir() + "map_builder_checkpoint_test.ot";
  std::ofstream(path, std::ios::binary) << earlier.fullWithProbabilities();

  MapBuilder restarted;
  restarted.load(path);
  EXPECT_EQ(restarted.fullWithProbabilities(), earlier.fullWithProbabilities());
  EXPECT_EQ(restarted.tree().getNumLeafNodes(), earlier.tree().getNumLeafNodes());
  std::size_t between = 0;  // cells not at a clamping bound: what a .bt would lose
  for (auto it = earlier.tree().begin_leafs(); it != earlier.tree().end_leafs(); ++it) {
    const octomap::OcTreeNode* node = restarted.tree().search(it.getKey());
    ASSERT_NE(node, nullptr);
    EXPECT_FLOAT_EQ(node->getLogOdds(), it->getLogOdds());
    between += it->getLogOdds() > earlier.tree().getClampingThresMinLog() &&
               it->getLogOdds() < earlier.tree().getClampingThresMaxLog();
  }
  EXPECT_GT(between, 0u) << "the test map should hold cells a .bt cannot express";

  const std::string before = restarted.fullWithProbabilities();
  const std::string damaged = testing::TempDir() + "map_builder_checkpoint_damaged.ot";
  const std::string text = earlier.fullWithProbabilities();
  std::ofstream(damaged, std::ios::binary) << text.substr(0, text.size() / 2);
  try {
    restarted.load(damaged);
    ADD_FAILURE() << "a cut checkpoint was loaded";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(damaged), std::string::npos) << error.what();
  }
  EXPECT_EQ(restarted.fullWithProbabilities(), before);
  std::remove(path.c_str());
  std::remove(damaged.c_str());
}

// An earlier mission's map as the start of the next: load() gives the saved map exactly, with
// nothing pending and a snapshot of it; a file it cannot take leaves the map as it was.
TEST(MapBuilderTest, LoadStartsFromASavedMapAndRefusesFilesItCannotTake) {
  MapBuilder earlier;
  insertRingOfReturns(earlier);
  const std::string path = testing::TempDir() + "map_builder_load_test.bt";
  ASSERT_TRUE(earlier.save(path));

  MapBuilder next;
  next.enableChangeTracking(true);
  next.load(path);
  EXPECT_EQ(next.fullBinary(), earlier.fullBinary());
  EXPECT_TRUE(isOccupied(next.tree(), 7.25, 0.25, 0.25));
  EXPECT_EQ(next.pendingChangeCount(), 0u);
  EXPECT_EQ(next.snapshot()->getNumLeafNodes(), next.tree().getNumLeafNodes());

  const auto refused = [](MapBuilder& builder, const std::string& file, const std::string& why) {
    const std::string before = builder.fullBinary();
    try {
      builder.load(file);
      ADD_FAILURE() << file << " was loaded";
    } catch (const std::runtime_error& error) {
      EXPECT_NE(std::string(error.what()).find(file), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find(why), std::string::npos) << error.what();
    }
    EXPECT_EQ(builder.fullBinary(), before);
  };
  MapBuilder::Options finer;
  finer.resolution = 0.25;
  MapBuilder other_resolution(finer);
  refused(other_resolution, path, "resolution 0.5");

  std::string bytes;
  {
    std::ifstream file(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(file), {});
  }
  const std::string truncated = testing::TempDir() + "map_builder_load_truncated.bt";
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  refused(next, truncated, "not an OctoMap binary");
  refused(next, testing::TempDir() + "no_such_map.bt", "cannot open");
  std::remove(path.c_str());
  std::remove(truncated.c_str());
}

TEST(MapBuilderTest, SnapshotsAreImmutableCopies) {
  MapBuilder builder;
  const auto empty = builder.snapshot();
  ASSERT_NE(empty, nullptr);
  EXPECT_EQ(empty->size(), 0u);
  BeamGeometry beam;
  beam.return_range = 4.0;
  builder.insertBeam(beam, sensorAt({0.1, 0.1, 0.1}, 0));
  EXPECT_EQ(builder.snapshot()->size(), 0u);  // not published yet
  const auto taken = builder.takeSnapshot();
  EXPECT_EQ(builder.snapshot(), taken);
  EXPECT_EQ(taken->size(), builder.tree().size());
  builder.clear();
  EXPECT_EQ(builder.tree().size(), 0u);
  EXPECT_TRUE(isOccupied(*taken, 4.25, 0.25, 0.25));  // readers keep their version
}

TEST(MapBuilderTest, SnapshotsAreCopiedOnlyForReadersThatAsk) {
  MapBuilder builder;
  BeamGeometry beam;
  beam.return_range = 4.0;
  builder.insertBeam(beam, sensorAt({0.1, 0.1, 0.1}, 0));
  EXPECT_FALSE(builder.refreshSnapshot());    // nobody asked
  EXPECT_EQ(builder.snapshot()->size(), 0u);  // asks; the copy comes with the next refresh
  EXPECT_TRUE(builder.refreshSnapshot());
  EXPECT_EQ(builder.snapshot()->size(), builder.tree().size());
  EXPECT_FALSE(builder.refreshSnapshot());  // asked, but nothing changed: no copy
  builder.insertBeam(beam, sensorAt({0.1, 2.1, 0.1}, 0));
  EXPECT_TRUE(builder.refreshSnapshot());  // the request waited for the change
  EXPECT_EQ(builder.snapshot()->size(), builder.tree().size());
  builder.clear();
  EXPECT_TRUE(builder.refreshSnapshot());
  EXPECT_EQ(builder.snapshot()->size(), 0u);
}

// Beams from a few poses: a map with pruned regions, several depths and both kinds of cells.
void addBeams(MapBuilder& builder, int beams) {
  builder.enableChangeTracking(true);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::uniform_real_distribution<double> range(1.0, 25.0);
  for (int i = 0; i < beams; ++i) {
    BeamGeometry beam;
    beam.direction = beamDirection(angle(random));
    const double r = range(random);
    if (r <= 20.0) beam.return_range = r;
    builder.insertBeam(beam, sensorAt({0.3 * (i % 7), -0.2 * (i % 5), 0.1 * (i % 3)}, 0.1 * i));
  }
}

TEST(OtStreamTest, WriteTreeIsByteForByteOctomapsWrite) {
  for (int beams : {0, 1, 500}) {
    MapBuilder builder;
    addBeams(builder, beams);
    std::ostringstream theirs;
    builder.tree().write(theirs);
    EXPECT_EQ(ot_stream::writeTree(builder.tree()), theirs.str()) << beams << " beams";
    EXPECT_EQ(builder.fullWithProbabilities(), theirs.str());
  }
}

// readTree gives the tree AbstractOcTree::read gives, without its debug lines on stderr, and
// refuses what is not a whole OcTree .ot stream.
TEST(OtStreamTest, ReadTreeReadsWhatOctomapWritesAndPrintsNothing) {
  for (int beams : {0, 1, 500}) {
    MapBuilder builder;
    addBeams(builder, beams);
    std::ostringstream theirs;
    builder.tree().write(theirs);
    std::istringstream input(theirs.str());
    testing::internal::CaptureStderr();
    testing::internal::CaptureStdout();
    const std::unique_ptr<octomap::OcTree> tree = ot_stream::readTree(input);
    EXPECT_EQ(testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr(), "");
    ASSERT_NE(tree, nullptr);
    EXPECT_DOUBLE_EQ(tree->getResolution(), kResolution);
    std::ostringstream again;
    tree->write(again);
    EXPECT_EQ(again.str(), theirs.str()) << beams << " beams";
  }
  MapBuilder builder;
  addBeams(builder, 10);
  const std::string whole = builder.fullWithProbabilities();
  for (const std::string& bad :
       {std::string("not a tree"), whole.substr(0, whole.size() / 2),
        std::string("# Octomap OcTree file\nid ColorOcTree\nsize 0\nres 0.1\ndata\n")}) {
    std::istringstream input(bad);
    EXPECT_THROW(ot_stream::readTree(input), std::runtime_error) << bad.substr(0, 40);
  }
}

// OctoMap's readers recurse as deep as the child bits say (a fuzzed .ot overflowed the stack):
// streams nested deeper than the tree, or that end early, are refused before OctoMap reads.
TEST(OtStreamTest, NodeDataDeeperThanTheTreeOrCutShortIsRefused) {
  // .ot: every node a float and one child: 17 levels fit a tree 16 deep, 18 do not.
  const auto chain = [](int nodes) {
    std::string data;
    for (int i = 0; i < nodes; ++i) data += std::string(4, '\0') + (i + 1 < nodes ? '\1' : '\0');
    return data;
  };
  EXPECT_EQ(ot_stream::otDataProblem(chain(17), 17), "");
  EXPECT_NE(ot_stream::otDataProblem(chain(18), 18).find("has children"), std::string::npos);
  const std::string deep = "# Octomap OcTree file\nid OcTree\nsize 100000\nres 0.5\ndata\n" +
                           std::string(100000, '\1');  // each node's bits: one child, forever
  std::istringstream deep_stream(deep);
  EXPECT_THROW(ot_stream::readTree(deep_stream), std::runtime_error);
  EXPECT_NE(ot_stream::otDataProblem(chain(5).substr(0, 12), 5).find("ends early"),
            std::string::npos);
  EXPECT_NE(ot_stream::otDataProblem(chain(5), 6).find("holds 5"), std::string::npos);

  // .bt: what OctoMap writes reads back; a chain of inner nodes 16 deep does not.
  MapBuilder builder;
  addBeams(builder, 50);
  const std::string binary = builder.fullBinary();
  std::istringstream input(binary);
  octomap::OcTree read(kResolution);
  ot_stream::readBinaryTree(input, read);
  EXPECT_EQ(read.size(), builder.tree().size());
  std::string inner_chain;
  for (int i = 0; i < 16; ++i) inner_chain += std::string("\3\0", 2);  // first child inner
  EXPECT_EQ(ot_stream::btDataProblem(inner_chain.substr(0, 30) + std::string(2, '\0')), "");
  EXPECT_NE(ot_stream::btDataProblem(inner_chain + std::string(2, '\0')).find("has children"),
            std::string::npos);
  for (const std::string& bad : {std::string("# Octomap OcTree binary file\nid OcTree\ndata"),
                                 std::string("# Octomap OcTree binary file\nid OcTree\ndata\n")}) {
    std::istringstream input(bad);  // a data line and no node
    EXPECT_THROW(ot_stream::readBinaryTree(input, read), std::runtime_error);
  }
  std::istringstream cut(binary.substr(0, binary.size() - 3));
  octomap::OcTree untouched(kResolution);
  EXPECT_THROW(ot_stream::readBinaryTree(cut, untouched), std::runtime_error);
}

TEST(OtStreamTest, WriteCellsIsWhatAnOcTreeOfTheCellsWrites) {
  // The diff as it was built before: an OcTree set lazily, inner nodes updated, then written.
  MapBuilder builder;
  addBeams(builder, 300);
  std::vector<ot_stream::Cell> cells;
  octomap::OcTree changes(kResolution);
  for (auto it = builder.tree().begin_leafs(); it != builder.tree().end_leafs(); ++it) {
    if (it.getDepth() != builder.tree().getTreeDepth()) continue;  // finest cells only
    cells.push_back({ot_stream::cellCode(it.getKey()), it->getLogOdds()});
    changes.setNodeValue(it.getKey(), it->getLogOdds(), true);
  }
  ASSERT_GT(cells.size(), 100u);
  changes.updateInnerOccupancy();
  std::ostringstream theirs;
  changes.write(theirs);
  EXPECT_EQ(ot_stream::writeCells(cells, kResolution), theirs.str());
  std::vector<ot_stream::Cell> none;
  std::ostringstream empty;
  octomap::OcTree(kResolution).write(empty);
  EXPECT_EQ(ot_stream::writeCells(none, kResolution), empty.str());
  // And the builder's own diff of everything it changed equals that kind of tree too.
  const MapBuilder::Diff diff = builder.takeDiff();
  std::istringstream stream(diff.data);
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(stream));
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  std::ostringstream rewritten;
  tree->write(rewritten);
  EXPECT_EQ(rewritten.str(), diff.data);
  EXPECT_EQ(diff.cell_count, tree->getNumLeafNodes());
}

TEST(ChangedCellsTest, KeepsTheNewestValuePerCellThroughGrowthAndClears) {
  detail::ChangedCells cells;
  std::map<std::tuple<int, int, int>, float> expected;
  std::mt19937 random(11);
  std::uniform_int_distribution<int> coordinate(32700, 32840);  // collisions and overwrites
  for (int round = 0; round < 3; ++round) {
    const int count = round == 1 ? 50 : 20000;  // grow, then shrink on clear, then grow again
    for (int i = 0; i < count; ++i) {
      const octomap::OcTreeKey key(coordinate(random), coordinate(random), coordinate(random));
      cells.set(key, static_cast<float>(i));
      expected[{key[0], key[1], key[2]}] = static_cast<float>(i);
    }
    ASSERT_EQ(cells.size(), expected.size());
    std::size_t seen = 0;
    cells.forEach([&](const octomap::OcTreeKey& key, float value) {
      EXPECT_EQ(value, (expected[{key[0], key[1], key[2]}]));
      ++seen;
    });
    EXPECT_EQ(seen, expected.size());
    cells.clear();
    expected.clear();
    EXPECT_TRUE(cells.empty());
  }
}

// insertPrior: a prior slab moved by a yaw and a sub-cell offset fills every map cell inside
// it (no holes where the turned grid spreads cells apart), at the scaled log-odds, tracked as
// changes; a cell the map already holds keeps its value.
TEST(MapBuilderTest, InsertPriorFillsTheMovedPriorWithoutHolesAndKeepsObservedCells) {
  octomap::OcTree prior(0.5);
  for (double x = 0.25; x < 10.0; x += 0.5) {
    for (double y = 0.25; y < 10.0; y += 0.5) prior.updateNode(x, y, 1.25, 3.0f);
  }
  Eigen::Isometry3d map_T_prior = Eigen::Isometry3d::Identity();
  map_T_prior.linear() =
      Eigen::AngleAxisd(7.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  map_T_prior.translation() = Eigen::Vector3d(0.3, 0.2, 0.0);
  MapBuilder builder;
  builder.enableChangeTracking(true);
  const Eigen::Vector3d observed(5.25, 5.25, 1.25);  // the vehicle saw it free
  builder.insertCloud({Eigen::Vector3d(5.25, 5.25, 4.25)}, Eigen::Vector3d(5.25, 5.25, 0.1), 0.0);
  const float observed_value =
      builder.tree().search(observed.x(), observed.y(), observed.z())->getLogOdds();
  builder.takeDiff();
  const InsertStats stats = builder.insertPrior(prior, map_T_prior, 0.5);
  EXPECT_GT(stats.occupied_cells, 390u);
  EXPECT_EQ(builder.pendingChangeCount(), stats.occupied_cells + stats.free_cells);
  const octomap::OcTree& tree = builder.tree();
  int inside = 0;
  for (double x = -2.25; x < 12.0; x += 0.5) {
    for (double y = -2.25; y < 12.0; y += 0.5) {
      const Eigen::Vector3d p = map_T_prior.inverse() * Eigen::Vector3d(x, y, 1.25);
      if (p.x() < 0.3 || p.x() > 9.7 || p.y() < 0.3 || p.y() > 9.7) continue;  // inside
      const octomap::OcTreeNode* cell = tree.search(x, y, 1.25);
      ASSERT_NE(cell, nullptr) << "a hole at " << x << ", " << y;
      if (std::abs(x - observed.x()) < 0.1 && std::abs(y - observed.y()) < 0.1) {
        EXPECT_EQ(cell->getLogOdds(), observed_value) << "the vehicle's evidence stays";
        continue;
      }
      EXPECT_FLOAT_EQ(cell->getLogOdds(), 0.5f * prior.search(p.x(), p.y(), p.z())->getLogOdds());
      ++inside;
    }
  }
  EXPECT_GT(inside, 300);
  MapBuilder other_resolution(MapBuilder::Options{1.0});
  EXPECT_THROW(other_resolution.insertPrior(prior, map_T_prior, 0.5), std::invalid_argument);
}

TEST(MapBuilderTest, RejectsBadOptions) {
  MapBuilder::Options options;
  options.prob_hit = 0.4;
  EXPECT_THROW(MapBuilder{options}, std::invalid_argument);
  options = {};
  options.resolution = 0.0;
  EXPECT_THROW(MapBuilder{options}, std::invalid_argument);
}

}  // namespace
}  // namespace auv::mapping
