// Consistency filtering and fusion with true depth maps; the depth-map and views files.
#include "auv/recon/dense/fusion.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/dense/depth_map.h"
#include "synthetic_scene.h"

namespace auv::recon::dense {
namespace {

std::vector<FusionView> trueFusionViews(const testing::Scene& scene, std::vector<View> views) {
  std::vector<FusionView> out;
  for (View& view : views) {
    FusionView fv;
    fv.depth = testing::render(scene, view);
    fv.view = view;
    fv.normals = normalsFromDepth(fv.depth, fv.view, 2);
    out.push_back(fv);
  }
  return out;
}

// Planted outliers (5 % of the depths moved by +25 %) are removed by the consistency check
// against four neighbours (two must agree within 1 %); true depths seen by >= 2 neighbours stay.
TEST(Consistency, RemovesPlantedOutliers) {
  testing::Scene scene;
  std::vector<FusionView> views = trueFusionViews(scene, testing::gridViews(3, 3, 0.35, 4.0));
  FusionView master = views[4];
  master.depth = master.depth.clone();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(0, 1);
  cv::Mat planted(master.depth.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < master.depth.rows; ++y) {
    for (int x = 0; x < master.depth.cols; ++x) {
      if (uniform(random) < 0.05) {
        master.depth.at<float>(y, x) *= 1.25f;
        planted.at<uint8_t>(y, x) = 1;
      }
    }
  }
  const std::vector<const FusionView*> neighbours = {&views[1], &views[3], &views[5], &views[7]};
  FusionOptions options;
  options.min_consistent = 2;
  const cv::Mat counts = consistentNeighbours(master, neighbours, options);
  const cv::Mat filtered = filterDepthMap(master, neighbours, options);
  size_t planted_total = 0, planted_kept = 0, good_seen = 0, good_kept = 0;
  for (int y = 0; y < master.depth.rows; ++y) {
    for (int x = 0; x < master.depth.cols; ++x) {
      const bool kept = filtered.at<float>(y, x) > 0;
      EXPECT_EQ(kept, counts.at<uint8_t>(y, x) >= 2);
      if (planted.at<uint8_t>(y, x)) {
        ++planted_total;
        planted_kept += kept;
        continue;
      }
      // Seen by >= 2 neighbours (true geometry): count the true depth's agreeing views.
      FusionView probe = views[4];
      int seen = 0;
      const Eigen::Vector3d world = probe.view.backProject(x, y, probe.depth.at<float>(y, x));
      for (const FusionView* n : neighbours) {
        const Eigen::Vector3d c = n->view.toCamera(world);
        const Eigen::Vector2d p = n->view.project(c);
        const int px = static_cast<int>(std::lround(p.x())),
                  py = static_cast<int>(std::lround(p.y()));
        if (px >= 0 && py >= 0 && px < n->depth.cols && py < n->depth.rows &&
            std::abs(n->depth.at<float>(py, px) - c.z()) < 0.005 * c.z()) {
          ++seen;
        }
      }
      if (seen >= 2) {
        ++good_seen;
        good_kept += kept;
      }
    }
  }
  ASSERT_GT(planted_total, 1000u);
  EXPECT_EQ(planted_kept, 0u);
  ASSERT_GT(good_seen, master.depth.total() / 2);
  EXPECT_GT(good_kept, 0.97 * good_seen);
}

// Two views of a slanted plane: every point on the plane, normals the plane's (towards the
// cameras), both images recorded, (almost) no pixel fused twice.
TEST(Fusion, TwoViewsOfAPlaneGiveAPlanarCloudWithTheRightNormals) {
  testing::Scene scene;
  scene.with_sphere = false;
  std::vector<View> two = {testing::downwardView(1, {-0.2, 0, 4}, 160, 120, 150),
                           testing::downwardView(2, {0.2, 0, 4}, 160, 120, 150)};
  std::vector<FusionView> views = trueFusionViews(scene, two);
  FusionOptions options;
  options.min_consistent = 1;
  options.pixel_step = 1;
  Fuser fuser(options);
  const FusionStats first = fuser.add(views[0], {&views[1]});
  const FusionStats second = fuser.add(views[1], {&views[0]});
  const FusedCloud& cloud = fuser.cloud();
  ASSERT_GT(first.points, views[0].depth.total() / 2);
  // The overlap was fused from the first master already: only pixels no projection hit.
  EXPECT_LT(second.points, first.points / 20);
  EXPECT_LT(cloud.size(), views[0].depth.total());
  EXPECT_EQ(cloud.size(), cloud.normals.size());
  EXPECT_EQ(cloud.size(), cloud.colors.size());
  double worst_distance = 0, worst_angle = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    worst_distance = std::max(worst_distance,
                              std::abs(scene.plane_normal.dot(cloud.positions[i].cast<double>())));
    // The cameras are above the plane (+z side): normals point up.
    worst_angle = std::max(
        worst_angle,
        std::acos(std::clamp(cloud.normals[i].cast<double>().dot(scene.plane_normal), -1.0, 1.0)) *
            180 / M_PI);
    EXPECT_EQ(cloud.images.of(i), (std::vector<uint32_t>{1, 2}));
  }
  EXPECT_LT(worst_distance, 1e-4) << "m";
  EXPECT_LT(worst_angle, 1.0) << "deg";
  // Colours come from the images: mean grey of the cloud near the images' mean.
  double cloud_grey = 0;
  for (const auto& c : cloud.colors) cloud_grey += (c[0] + c[1] + c[2]) / 3.0;
  cloud_grey /= cloud.size();
  EXPECT_NEAR(cloud_grey, cv::mean(views[0].view.grey)[0], 15);
}

TEST(Fusion, ColourImageOfAnotherSizeIsRejected) {
  testing::Scene scene;
  std::vector<FusionView> views =
      trueFusionViews(scene, {testing::downwardView(1, {0, 0, 4}, 80, 60, 80)});
  views[0].view.color = cv::Mat(10, 10, CV_8UC3);
  Fuser fuser{FusionOptions()};
  EXPECT_THROW(fuser.add(views[0], {}), std::invalid_argument);
  FusionOptions bad;
  bad.depth_tolerance = 0;
  EXPECT_THROW(Fuser{bad}, OptionError);
}

class Files : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ =
        std::filesystem::temp_directory_path() / ("dense_files_" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }
  std::filesystem::path folder_;
};

TEST_F(Files, DepthArrayRoundTripAndBadFiles) {
  cv::Mat depth(7, 11, CV_32F);
  cv::randu(depth, 0.5, 9.0);
  writeDenseArray(folder_ / "a.depth.bin", depth);
  const cv::Mat back = readDenseArray(folder_ / "a.depth.bin");
  ASSERT_EQ(back.size(), depth.size());
  EXPECT_EQ(cv::norm(back, depth, cv::NORM_INF), 0.0);
  // COLMAP's header.
  std::ifstream in(folder_ / "a.depth.bin", std::ios::binary);
  std::string header(7, ' ');
  in.read(header.data(), 7);
  EXPECT_EQ(header, "11&7&1&");
  cv::Mat three(4, 5, CV_32FC3, cv::Scalar(1, 2, 3));
  writeDenseArray(folder_ / "n.bin", three);
  EXPECT_EQ(cv::norm(readDenseArray(folder_ / "n.bin"), three, cv::NORM_INF), 0.0);

  std::filesystem::resize_file(folder_ / "a.depth.bin", 40);
  try {
    readDenseArray(folder_ / "a.depth.bin");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("a.depth.bin: truncated"), std::string::npos) << e.what();
  }
  std::ofstream(folder_ / "bad.bin") << "11&x&1&";
  EXPECT_THROW(readDenseArray(folder_ / "bad.bin"), std::runtime_error);
  EXPECT_THROW(readDenseArray(folder_ / "missing.bin"), std::runtime_error);
}

TEST_F(Files, FusedViewsRoundTripAndTruncation) {
  PointViews images;
  images.add({1, 2});
  images.add({3});
  images.add({2, 5, 9});
  writeFusedViews(folder_ / "fused_views.bin", images);
  EXPECT_EQ(readFusedViews(folder_ / "fused_views.bin"),
            (std::vector<std::vector<uint32_t>>{{1, 2}, {3}, {2, 5, 9}}));
  const PointViews back = readPointViews(folder_ / "fused_views.bin");
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back.of(0), (std::vector<uint32_t>{1, 2}));
  EXPECT_EQ(back.of(1), (std::vector<uint32_t>{3}));
  EXPECT_EQ(back.of(2), (std::vector<uint32_t>{2, 5, 9}));
  std::filesystem::resize_file(folder_ / "fused_views.bin", 20);
  EXPECT_THROW(readFusedViews(folder_ / "fused_views.bin"), std::runtime_error);
}

}  // namespace
}  // namespace auv::recon::dense
