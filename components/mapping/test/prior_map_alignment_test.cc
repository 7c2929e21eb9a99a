// PriorMapAlignment on synthetic sites (synthetic_scene.h): a prior map built from a first
// visit, saved and loaded as a .bt like initial_map; a second visit's returns seen from a
// navigation frame offset by (2.5 m, -1.5 m, yaw 4 deg). The transform is recovered; a changed
// site (a boulder gone, one added) still aligns and, once the prior is in the map, beams through
// the gone boulder clear it; one straight wall is DEGENERATE; an unrelated site FAILS.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "auv/mapping/map_builder.h"
#include "auv/mapping/prior_map_alignment.h"
#include "synthetic_scene.h"

namespace auv::mapping {
namespace {

using test::castFan;
using test::Scene;

constexpr double kDegree = M_PI / 180.0;

/// navigation_T_prior of the second visit.
Eigen::Isometry3d navigationOffset() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(4.0 * kDegree, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(2.5, -1.5, 0.0);
  return t;
}

/// The first visit's map as initial_map would hold it: built, saved as .bt, loaded.
std::unique_ptr<octomap::OcTree> priorMap(const Scene& scene, double x_from, double x_to) {
  MapBuilder first;
  test::mapVisit(first, scene, x_from, x_to);
  // One file per test and process: CTest runs this binary's tests in parallel.
  const std::string path = testing::TempDir() + "prior_map_alignment_" +
                           testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           std::to_string(getpid()) + ".bt";
  EXPECT_TRUE(first.save(path));
  MapBuilder loader;
  loader.load(path);
  std::remove(path.c_str());
  return std::make_unique<octomap::OcTree>(loader.tree());
}

/// A second visit along y = 1, z = 2.5 in the true frame, returns given in the navigation frame;
/// attempts whenever due. Inserts the same rays into `live` (navigation frame) if given, as the
/// mapping component does. Stops when the alignment finishes.
const AlignmentResult& secondVisit(PriorMapAlignment& alignment, const Scene& scene, double x_from,
                                   double x_to, MapBuilder* live = nullptr) {
  const Eigen::Isometry3d navigation_T_world = navigationOffset();
  for (double x = x_from; x <= x_to + 1e-9 && !alignment.result().finished; x += 1.0) {
    const Eigen::Vector3d origin(x, 1.0, 2.5);
    const test::Fan fan = castFan(scene, origin);
    std::vector<Eigen::Vector3d> points;
    for (std::size_t i = 0; i < fan.points.size(); ++i) {
      points.push_back(navigation_T_world * fan.points[i]);
      if (fan.is_return[i]) alignment.addReturn(points.back());
    }
    if (live) live->insertCloud(points, navigation_T_world * origin, 20.0);
    if (alignment.attemptDue()) {
      const auto start = std::chrono::steady_clock::now();
      const AlignmentResult& r = alignment.attempt();
      const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
      std::cout << "attempt " << r.attempts << " at " << r.points_collected << " in "
                << took.count() << " s: " << toString(r.state) << " (" << r.reason << ")"
                << std::endl;
    }
  }
  return alignment.result();
}

PriorMapAlignment::Options testOptions() {
  PriorMapAlignment::Options options;
  options.min_points = 1500;
  options.retry_points = 500;
  options.max_points = 6000;
  return options;
}

void expectOffsetRecovered(const AlignmentResult& r) {
  std::cout << "recovered x " << r.x_m << " y " << r.y_m << " z " << r.z_m << " yaw "
            << r.yaw_rad / kDegree << " deg; inliers " << r.inlier_fraction << ", rms " << r.rms_m
            << ", ambiguity " << r.ambiguity_ratio << ", constraint " << r.constraint << ", points "
            << r.points_used << " of " << r.points_collected << std::endl;
  EXPECT_NEAR(r.x_m, 2.5, 0.15);
  EXPECT_NEAR(r.y_m, -1.5, 0.15);
  EXPECT_NEAR(r.z_m, 0.0, 1e-9);
  EXPECT_NEAR(r.yaw_rad / kDegree, 4.0, 0.5);
}

/// Occupied cells of `map` on or in `sphere` (within 0.3 m of its surface) moved into the
/// navigation frame,
/// above the seabed's cells.
int occupiedInside(const octomap::OcTree& map, const test::Sphere& sphere) {
  const Eigen::Vector3d centre = navigationOffset() * sphere.centre;
  int count = 0;
  for (auto it = map.begin_leafs(); it != map.end_leafs(); ++it) {
    const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
    if (map.isNodeOccupied(*it) && c.z() < 7.5 && (c - centre).norm() < sphere.radius + 0.3) {
      ++count;
    }
  }
  return count;
}

/// An occupied cell within one cell of `p` (a surface point).
bool occupiedNear(const octomap::OcTree& map, const Eigen::Vector3d& p) {
  const double step = map.getResolution();
  for (double dx = -step; dx <= step; dx += step) {
    for (double dy = -step; dy <= step; dy += step) {
      for (double dz = -step; dz <= step; dz += step) {
        const octomap::OcTreeNode* cell = map.search(p.x() + dx, p.y() + dy, p.z() + dz);
        if (cell != nullptr && map.isNodeOccupied(cell)) return true;
      }
    }
  }
  return false;
}

TEST(PriorMapAlignmentTest, RecoversTheNavigationFrameOffsetInACanyon) {
  const Scene canyon = test::canyonScene();
  PriorMapAlignment alignment(priorMap(canyon, -24.0, 26.0), testOptions());
  const AlignmentResult& result = secondVisit(alignment, canyon, -15.0, 15.0);
  ASSERT_EQ(result.state, AlignmentState::ALIGNED) << result.reason;
  EXPECT_TRUE(result.finished);
  EXPECT_GE(result.inlier_fraction, 0.8);
  expectOffsetRecovered(result);
  EXPECT_FALSE(alignment.attemptDue());
}

TEST(PriorMapAlignmentTest, AChangedSiteStillAlignsAndBeamsClearTheGoneBoulder) {
  Scene before = test::canyonScene();
  const test::Sphere kept_gone = {{-6.8, -2.6, 7.2}, 1.8};  // gone, inside the collected area
  const test::Sphere far_gone = {{24.0, -2.0, 7.1}, 1.9};   // gone, beyond it
  before.boulders.push_back(kept_gone);
  before.boulders.push_back(far_gone);
  Scene after = test::canyonScene();
  const test::Sphere added = {{-12.9, 3.4, 7.0}, 2.0};
  after.boulders.push_back(added);

  for (const double scale : {0.5, 1.0}) {
    SCOPED_TRACE(scale);
    PriorMapAlignment::Options options = testOptions();
    options.log_odds_scale = scale;
    PriorMapAlignment alignment(priorMap(before, -24.0, 30.0), options);
    MapBuilder live;
    const AlignmentResult& result = secondVisit(alignment, after, -18.0, 2.0, &live);
    ASSERT_EQ(result.state, AlignmentState::ALIGNED) << result.reason;
    expectOffsetRecovered(result);
    ASSERT_GT(occupiedInside(live.tree(), added), 5) << "the vehicle saw the new boulder";

    const InsertStats inserted =
        live.insertPrior(alignment.prior(), result.navigation_T_prior, options.log_odds_scale);
    EXPECT_GT(inserted.occupied_cells, 1000u);
    EXPECT_GT(inserted.free_cells, 10000u);
    // The vehicle's own evidence stays: the new boulder is there, the gone one seen through.
    EXPECT_GT(occupiedInside(live.tree(), added), 5);
    MapBuilder prior_only;  // what the prior alone puts there
    prior_only.insertPrior(alignment.prior(), result.navigation_T_prior, options.log_odds_scale);
    const int gone_in_prior = occupiedInside(prior_only.tree(), kept_gone);
    ASSERT_GT(gone_in_prior, 10);
    // Cells the vehicle saw through stay free; only unobserved ones at its foot take the prior.
    EXPECT_LE(occupiedInside(live.tree(), kept_gone), gone_in_prior / 5) << "of " << gone_in_prior;
    // The prior's walls at the moved place: the canyon wall at x = 20 (not visited again).
    for (double x : {20.0, 24.0}) {
      const double wall_y = 7.0 + 0.8 * std::sin(2.0 * M_PI * x / 13.0);
      EXPECT_TRUE(occupiedNear(live.tree(), navigationOffset() * Eigen::Vector3d(x, wall_y, 4.0)))
          << x;
    }
    // The top of the boulder at x = 21 where the moved prior puts it, not where it was.
    const Eigen::Vector3d boulder_top(21.0, 1.4, 5.2);
    EXPECT_TRUE(occupiedNear(live.tree(), navigationOffset() * boulder_top));
    EXPECT_FALSE(occupiedNear(live.tree(), boulder_top));

    // The far boulder came in with the prior; passes of beams through where it was clear it.
    const int before_passes = occupiedInside(live.tree(), far_gone);
    ASSERT_GT(before_passes, 10);
    const Eigen::Vector3d origin(16.0, -1.0, 4.0);
    int passes = 0;
    while (occupiedInside(live.tree(), far_gone) > 0 && passes < 12) {
      const test::Fan fan = castFan(after, origin, 20.0, 1.0, 4.0);
      std::vector<Eigen::Vector3d> points;
      for (const auto& p : fan.points) points.push_back(navigationOffset() * p);
      live.insertCloud(points, navigationOffset() * origin, 20.0);
      ++passes;
    }
    std::cout << "log_odds_scale " << scale << ": " << before_passes
              << " occupied cells of the gone boulder cleared after " << passes << " passes"
              << std::endl;
    EXPECT_EQ(occupiedInside(live.tree(), far_gone), 0);
    if (scale == 0.5) {
      EXPECT_LE(passes, 5);
    } else {
      EXPECT_GT(passes, 5) << "a full-confidence prior resists longer";
    }
  }
}

TEST(PriorMapAlignmentTest, OneStraightWallIsDegenerateNotAWrongTransform) {
  Scene wall;
  wall.straight_wall = true;
  PriorMapAlignment::Options options = testOptions();
  options.min_points = 800;
  options.max_points = 3000;
  PriorMapAlignment alignment(priorMap(wall, -40.0, 40.0), options);
  const AlignmentResult& result = secondVisit(alignment, wall, -14.0, 40.0);
  EXPECT_EQ(result.state, AlignmentState::DEGENERATE) << result.reason;
  EXPECT_TRUE(result.finished) << result.points_collected << " points";
  EXPECT_LT(result.constraint, options.min_constraint);
  EXPECT_NE(result.reason.find("max_points"), std::string::npos) << result.reason;
}

TEST(PriorMapAlignmentTest, AnUnrelatedSiteFailsAfterMaxPoints) {
  Scene pillars;
  for (int i = 0; i < 24; ++i) {  // a deterministic scatter over 40 x 24 m
    const double x = -20.0 + std::fmod(i * 7.3, 40.0), y = -12.0 + std::fmod(i * 5.9, 24.0);
    pillars.pillars.push_back({{x, y}, 0.6 + 0.05 * (i % 9)});
  }
  PriorMapAlignment::Options options = testOptions();
  options.max_points = 4000;
  PriorMapAlignment alignment(priorMap(test::canyonScene(), -24.0, 26.0), options);
  const AlignmentResult& result = secondVisit(alignment, pillars, -20.0, 40.0);
  EXPECT_EQ(result.state, AlignmentState::FAILED) << result.reason;
  EXPECT_TRUE(result.finished);
  EXPECT_GE(result.points_collected, 4000u);
  EXPECT_LT(result.inlier_fraction, options.min_inlier_fraction);
  EXPECT_GE(result.attempts, 2);
}

TEST(PriorMapAlignmentTest, OptionsAreCheckedNamingTheField) {
  PriorMapAlignment::Options options;
  options.max_points = 100;
  try {
    options.check();
    ADD_FAILURE() << "max_points < min_points accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("max_points"), std::string::npos) << error.what();
  }
  options = {};
  options.log_odds_scale = 0.0;
  EXPECT_THROW(options.check(), std::invalid_argument);
  EXPECT_THROW(PriorMapAlignment(nullptr, PriorMapAlignment::Options{}), std::invalid_argument);
}

}  // namespace
}  // namespace auv::mapping
