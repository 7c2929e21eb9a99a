// MapFollower: the controller's copy of the map, applied on a thread of its own (no DDS).
#include "auv/control/components/map_follower.h"

#include <gtest/gtest.h>

#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <octomap/OcTree.h>

#include "full_map_update.h"

namespace auv::control {
namespace {

using test::fullMapUpdate;

msg::OctomapUpdate unreadableMap(uint64_t sequence) {
  msg::OctomapUpdate update = fullMapUpdate(octomap::OcTree(0.5), sequence);
  update.data({'n', 'o', 't', ' ', 'a', ' ', 'm', 'a', 'p'});
  return update;
}

octomap::OcTree rock() {
  octomap::OcTree tree(0.5);
  tree.updateNode(octomap::point3d(1.25, 2.25, 3.25), true);
  return tree;
}

bool occupiedAt(const MapFollower& follower, const octomap::point3d& point) {
  bool occupied = false;
  EXPECT_TRUE(follower.tryRead([&](const octomap::OcTree& tree) {
    const octomap::OcTreeNode* node = tree.search(point);
    occupied = node != nullptr && tree.isNodeOccupied(node);
  }));
  return occupied;
}

// Collects reports from whichever thread makes them.
struct Reports {
  void add(uint64_t sequence, const std::string& error) {
    std::lock_guard<std::mutex> lock(mutex);
    sequences.push_back(sequence);
    errors.push_back(error);
    threads.push_back(std::this_thread::get_id());
  }
  std::mutex mutex;
  std::vector<uint64_t> sequences;
  std::vector<std::string> errors;
  std::vector<std::thread::id> threads;
};

TEST(MapFollowerTest, UpdatesAreAppliedInOrderOffThePushingThread) {
  Reports reports;
  MapFollower follower("octomap", 0.5, [&](uint64_t sequence, const std::string& error) {
    reports.add(sequence, error);
  });
  EXPECT_EQ(follower.sequence(), 0u);
  follower.push(fullMapUpdate(rock(), 4));
  follower.push(unreadableMap(5));
  follower.waitIdle();
  // The unreadable one is reported and leaves the copy as the first made it.
  EXPECT_EQ(follower.sequence(), 4u);
  EXPECT_TRUE(occupiedAt(follower, {1.25f, 2.25f, 3.25f}));
  EXPECT_FALSE(occupiedAt(follower, {0.25f, 0.25f, 0.25f}));
  ASSERT_EQ(reports.sequences.size(), 1u);
  EXPECT_EQ(reports.sequences[0], 5u);
  EXPECT_FALSE(reports.errors[0].empty());
  // Read on the follower's thread, not the caller's (in the component: the control thread).
  EXPECT_NE(reports.threads[0], std::this_thread::get_id());
}

TEST(MapFollowerTest, AnOverflowingQueueDropsTheOldestAndSaysSo) {
  Reports reports;
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::promise<void> blocked;
  MapFollower follower(
      "octomap", 0.5,
      [&](uint64_t sequence, const std::string& error) {
        reports.add(sequence, error);
        if (sequence == 1) {  // hold the follower's thread inside its first report
          blocked.set_value();
          released.wait();
        }
      },
      /*max_queued=*/2);
  follower.push(unreadableMap(1));
  blocked.get_future().wait();
  for (uint64_t sequence = 2; sequence <= 5; ++sequence)
    follower.push(fullMapUpdate(rock(), sequence));
  release.set_value();
  follower.waitIdle();
  // 2 and 3 were dropped; 4 and 5 applied.
  EXPECT_EQ(follower.sequence(), 5u);
  std::lock_guard<std::mutex> lock(reports.mutex);
  ASSERT_EQ(reports.errors.size(), 3u);
  EXPECT_NE(reports.errors[1].find("1 update(s) dropped"), std::string::npos) << reports.errors[1];
  EXPECT_EQ(reports.sequences[1], 2u);
  EXPECT_EQ(reports.sequences[2], 3u);
}

TEST(MapFollowerTest, AnotherMapOrResolutionLeavesTheCopyAlone) {
  Reports reports;
  MapFollower follower("octomap", 0.5, [&](uint64_t sequence, const std::string& error) {
    reports.add(sequence, error);
  });
  msg::OctomapUpdate other = fullMapUpdate(rock(), 1);
  other.map_id("another");
  follower.push(other);
  follower.push(fullMapUpdate(octomap::OcTree(0.25), 2));
  follower.waitIdle();
  EXPECT_EQ(follower.sequence(), 0u);
  ASSERT_EQ(reports.errors.size(), 1u);  // another map is not this reader's business
  EXPECT_NE(reports.errors[0].find("resolution"), std::string::npos) << reports.errors[0];
}

TEST(MapFollowerTest, DestroyedWithUpdatesStillQueued) {
  const msg::OctomapUpdate update = fullMapUpdate(rock(), 1);
  auto follower = std::make_unique<MapFollower>("octomap", 0.5, nullptr);
  for (int i = 0; i < 50; ++i) follower->push(update);
  follower.reset();  // returns: the thread stops without applying the rest
  SUCCEED();
}

}  // namespace
}  // namespace auv::control
