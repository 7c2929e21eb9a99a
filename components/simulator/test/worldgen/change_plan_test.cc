// `auv sim generate <world> --epoch 2`: seeded changes placed where the cameras film the first
// query, a later-visit scenario that loads with them applied, and the same seed giving the same
// changes.
#include "auv/sim/worldgen/change_plan.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <fstream>
#include <sstream>

#include "auv/sim/world/change_truth.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/generate_cli.h"

namespace auv::sim {
namespace {

namespace fs = std::filesystem;

GeneratedWorld canyon(double detail = 0.3) {
  WorldGenOptions options;
  options.seed = 1;
  options.detail = detail;
  return generateWorld("canyon", options);
}

/// Horizontal distance from `p` to the polyline.
double distanceToRoute(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& route) {
  double best = 1e9;
  for (size_t i = 1; i < route.size(); ++i) {
    const Eigen::Vector2d a = route[i - 1].head<2>(), b = route[i].head<2>();
    const double t =
        std::clamp((p.head<2>() - a).dot(b - a) / std::max(1e-9, (b - a).squaredNorm()), 0.0, 1.0);
    best = std::min(best, (p.head<2>() - (a + t * (b - a))).norm());
  }
  return best;
}

TEST(ChangePlanTest, CanyonGetsEveryKindUnderTheFirstTraverseAndTheSameSeedTheSameChanges) {
  const GeneratedWorld world = canyon();
  ChangePlanOptions options;
  options.seed = 3;
  const std::vector<SiteChange> changes = planSiteChanges(world, options);
  std::set<std::string> names;
  for (const SiteChange& c : changes) {
    names.insert(c.name);
    // Filmed from the route: within the side cameras' reach of it, below it.
    EXPECT_LT(distanceToRoute(c.center, world.layout.routes[0]), 4.5) << c.name;
    EXPECT_GT(c.center.z(), world.layout.routes[0].front().z()) << c.name;
  }
  for (const char* name : {"fallen_block", "growth", "scour", "bleached_patch"})
    EXPECT_TRUE(names.count(name)) << name;
  EXPECT_EQ(siteChangesYaml(planSiteChanges(world, options)), siteChangesYaml(changes));
  options.seed = 4;
  EXPECT_NE(siteChangesYaml(planSiteChanges(world, options)), siteChangesYaml(changes));
}

TEST(ChangePlanTest, GenerateEpoch2WritesALaterVisitThatLoadsWithItsTruth) {
  const fs::path dir =
      fs::temp_directory_path() / ("auv_change_plan_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  std::ostringstream out, err;
  ASSERT_EQ(runGenerateCommand({"canyon", "--detail", "0.3", "--epoch", "2", "--changes-seed", "2",
                                "--out", dir.string()},
                               out, err),
            0)
      << err.str();
  ASSERT_TRUE(fs::is_regular_file(dir / "canyon.yaml"));
  const Scenario later = loadScenario((dir / "canyon_epoch2.yaml").string());
  EXPECT_EQ(later.name, "canyon_epoch2");
  EXPECT_GE(later.changes.size(), 4u);
  EXPECT_TRUE(loadScenario((dir / "canyon.yaml").string()).changes.empty());
  ASSERT_TRUE(writeScenarioChangeTruth(later, (dir / "truth").string()));
  EXPECT_TRUE(fs::is_regular_file(dir / "truth" / "changes.ply"));
  EXPECT_TRUE(fs::is_regular_file(dir / "truth" / "world.ply"));
  // Every geometric change is at least 10 cm somewhere (what the comparison must detect).
  std::vector<AppliedChange> applied;
  const Mesh after = loadWorldMesh(later, nullptr, &applied);
  const ChangeTruth truth = measureChangeTruth(loadWorldMeshBeforeChanges(later), after, applied);
  for (const ChangeTruthRegion& r : truth.regions) {
    if (r.geometric) {
      EXPECT_GE(std::abs(r.max_distance_m), 0.1) << r.name;
    }
    EXPECT_GT(r.points, 100u) << r.name;
  }
  fs::remove_all(dir);

  EXPECT_EQ(runGenerateCommand({"canyon", "--epoch", "3"}, out, err), 2);
  EXPECT_NE(err.str().find("--epoch: expected 1"), std::string::npos) << err.str();
  EXPECT_EQ(runGenerateCommand({"canyon", "--epoch", "2", "--changes-along", "0.6,0.2"}, out, err),
            2);
  EXPECT_NE(err.str().find("--changes-along: expected 0 <= from < to <= 1"), std::string::npos)
      << err.str();
}

TEST(ChangePlanTest, NoChangesWritesAControlVisitWithAnEmptyTruth) {
  const fs::path dir =
      fs::temp_directory_path() / ("auv_change_control_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  std::ostringstream out, err;
  ASSERT_EQ(runGenerateCommand(
                {"canyon", "--detail", "0.3", "--epoch", "2", "--no-changes", "--out", dir.string()},
                out, err),
            0)
      << err.str();
  const Scenario later = loadScenario((dir / "canyon_epoch2.yaml").string());
  EXPECT_TRUE(later.changes.empty());
  EXPECT_TRUE(later.later_visit);
  EXPECT_FALSE(loadScenario((dir / "canyon.yaml").string()).later_visit);
  ASSERT_TRUE(writeScenarioChangeTruth(later, (dir / "truth").string()));
  std::ifstream json(dir / "truth" / "changes.json");
  const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"regions\": []"), std::string::npos) << text;
  EXPECT_TRUE(fs::is_regular_file(dir / "truth" / "world.ply"));
  EXPECT_FALSE(writeScenarioChangeTruth(loadScenario((dir / "canyon.yaml").string()),
                                        (dir / "none").string()));
  fs::remove_all(dir);

  EXPECT_EQ(runGenerateCommand({"canyon", "--no-changes"}, out, err), 2);
  EXPECT_NE(err.str().find("--no-changes is for --epoch 2"), std::string::npos) << err.str();
}

}  // namespace
}  // namespace auv::sim
