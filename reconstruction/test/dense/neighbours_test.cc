// Neighbour selection and depth ranges from a synthetic sparse model.
#include "auv/recon/dense/neighbours.h"

#include <gtest/gtest.h>

#include "auv/recon/common/stage_error.h"
#include "synthetic_scene.h"

namespace auv::recon::dense {
namespace {

TEST(Neighbours, CovisibleViewsAtAGoodAngleAndADepthRangeAroundTheTruth) {
  testing::Scene scene;
  std::vector<View> views = testing::gridViews(3, 3, 0.35, 4.0, 120, 90, 110);
  // A tenth view far away: it shares no point with the others.
  views.push_back(testing::downwardView(10, {30, 30, 4}, 120, 90, 110));
  // An eleventh at the centre's position: no baseline.
  views.push_back(
      testing::downwardView(11, views[4].center() + Eigen::Vector3d(0.001, 0, 0), 120, 90, 110));
  std::vector<cv::Mat> depths;
  for (View& view : views) depths.push_back(testing::render(scene, view));
  const scene::Reconstruction model = testing::sparseModel(views, depths, 6);

  NeighbourOptions options;
  options.max_neighbours = 4;
  const std::vector<MasterSelection> selections = selectNeighbours(model, options);
  ASSERT_EQ(selections.size(), views.size());
  const MasterSelection& centre = selections[4];
  ASSERT_EQ(centre.master, 5u);
  ASSERT_TRUE(centre.usable());
  EXPECT_EQ(centre.neighbours.size(), 4u);
  for (size_t i = 0; i < centre.neighbours.size(); ++i) {
    EXPECT_NE(centre.neighbours[i], 10u) << "no shared points";
    EXPECT_NE(centre.neighbours[i], 11u) << "no baseline";
    EXPECT_GE(centre.shared_points[i], options.min_shared_points);
    EXPECT_GE(centre.angle_deg[i], options.min_angle_deg);
    EXPECT_LE(centre.angle_deg[i], options.max_angle_deg);
    if (i > 0) {
      EXPECT_GE(centre.shared_points[i - 1] *
                    std::pow(std::min(1.0, centre.angle_deg[i - 1] / options.good_angle_deg), 2),
                centre.shared_points[i] *
                    std::pow(std::min(1.0, centre.angle_deg[i] / options.good_angle_deg), 2))
          << "best first";
    }
  }
  double true_min = 1e9, true_max = 0;
  depths[4].forEach<float>([&](float d, const int*) {
    if (d > 0) true_min = std::min<double>(true_min, d), true_max = std::max<double>(true_max, d);
  });
  EXPECT_LT(centre.depth_min, true_min);
  EXPECT_GT(centre.depth_max, true_max);
  EXPECT_GT(centre.depth_min, 0.5 * true_min);
  EXPECT_LT(centre.depth_max, 2.0 * true_max);
  // The far view has no neighbours: not usable as a master.
  EXPECT_FALSE(selections[9].usable());
}

TEST(Neighbours, OptionsRejectBadValuesNamingTheField) {
  NeighbourOptions options;
  options.max_neighbours = 0;
  try {
    options.check();
    FAIL() << "no error";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("max_neighbours = 0"), std::string::npos) << e.what();
  }
  options = NeighbourOptions();
  options.max_angle_deg = 1.0;  // below min_angle_deg
  EXPECT_THROW(options.check(), OptionError);
  options = NeighbourOptions();
  options.depth_percentile = 0.5;
  EXPECT_THROW(options.check(), OptionError);
}

}  // namespace
}  // namespace auv::recon::dense
