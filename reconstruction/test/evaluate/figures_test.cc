// Figures 19 and 20: colours of camera combinations, top-down drawing at known places, the
// per-camera figure of a two-camera survey, the trajectory figure with ground truth, bad inputs.
#include "auv/recon/evaluate/figures.h"

#include <gtest/gtest.h>

#include <fstream>

#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/stage_error.h"
#include "synthetic_survey.h"

namespace auv::recon::evaluate {
namespace {

namespace fs = std::filesystem;
using testing::SyntheticSurvey;

TEST(CombinationColor, PaperStyleLegend) {
  EXPECT_EQ(combinationColor(0b001, 3), cv::Vec3b(40, 40, 255));    // first camera: red
  EXPECT_EQ(combinationColor(0b010, 3), cv::Vec3b(40, 255, 40));    // second: green
  EXPECT_EQ(combinationColor(0b100, 3), cv::Vec3b(255, 40, 40));    // third: blue
  EXPECT_EQ(combinationColor(0b011, 3), cv::Vec3b(40, 255, 255));   // first + second: yellow
  EXPECT_EQ(combinationColor(0b111, 3), cv::Vec3b(255, 255, 255));  // all: white
  EXPECT_NE(combinationColor(0b0011, 5), combinationColor(0b0101, 5));
  EXPECT_EQ(combinationName(0b101, {"forward", "left", "right"}), "forward + right");
}

TEST(TopDown, ShallowPointsCoverDeepOnesAtTheirPlaces) {
  // NED: north up, east right; at (0, 0) a deep red point under a shallow green one; at
  // (10, 0) (north) a blue one, at (0, 10) (east) a white one.
  const std::vector<Eigen::Vector3d> points{{0, 0, 5}, {0, 0, 1}, {10, 0, 3}, {0, 10, 3}};
  const std::vector<cv::Vec3b> colors{{0, 0, 255}, {0, 255, 0}, {255, 0, 0}, {255, 255, 255}};
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : points) xy.push_back(p.head<2>());
  const TopDownView view(xy, 400);
  EXPECT_EQ(view.size(), cv::Size(400, 400));
  const cv::Mat image = drawTopDownCloud(points, colors, view, 3);
  auto at = [&](const Eigen::Vector2d& p) {
    const cv::Point2f q = view.pixel(p);
    return image.at<cv::Vec3b>(static_cast<int>(std::lround(q.y)),
                               static_cast<int>(std::lround(q.x)));
  };
  EXPECT_EQ(at({0, 0}), cv::Vec3b(0, 255, 0));
  EXPECT_EQ(at({10, 0}), cv::Vec3b(255, 0, 0));
  EXPECT_EQ(at({0, 10}), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(at({5, 5}), cv::Vec3b(30, 30, 30));  // background
  // North is up, east is right.
  EXPECT_LT(view.pixel({10, 0}).y, view.pixel({0, 0}).y);
  EXPECT_GT(view.pixel({0, 10}).x, view.pixel({0, 0}).x);
}

/// A sparse model of two cameras, "left" and "right": points x < -1 seen by left only, x > 1
/// by right only, in [-1, 1] by both (one image of each).
void writeTwoCameraModel(const fs::path& survey) {
  scene::Reconstruction model;
  model.cameras[1] = scene::Camera::pinhole(1, 320, 240, 160, 160, 159.5, 119.5);
  model.images[1] = testing::downCamera(1, 1, {-2, 0, 0}, "left/left_0001_000000.png");
  model.images[2] = testing::downCamera(2, 1, {2, 0, 0}, "right/right_0001_000000.png");
  uint64_t id = 1;
  for (int i = -40; i <= 40; ++i) {
    for (int j = -10; j <= 10; ++j) {
      const double x = 0.1 * i, y = 0.1 * j;
      scene::Point3D point;
      point.id = id++;
      point.xyz = Eigen::Vector3d(x, y, 3 + 0.1 * std::sin(x));  // a gently curved seabed
      for (uint32_t image_id : {1u, 2u}) {
        if ((image_id == 1 && i > 10) || (image_id == 2 && i < -10)) continue;
        scene::Image& image = model.images[image_id];
        image.points2d.push_back(model.cameras[1].project(image.toCamera(point.xyz)));
        image.point3d_ids.push_back(static_cast<int64_t>(point.id));
        point.track.push_back({image_id, static_cast<uint32_t>(image.points2d.size() - 1)});
      }
      model.points[point.id] = point;
    }
  }
  scene::writeColmapText(model, survey / "sparse");
}

TEST(Figures, PerCameraContributionOfTwoCameras) {
  const fs::path survey = testing::freshFolder("figures_two_cameras");
  writeTwoCameraModel(survey);
  FiguresOptions options;
  options.image_size_px = 600;
  options.point_size_px = 3;
  const FiguresResult result = writeFigures(Survey(survey), {}, options);
  EXPECT_EQ(result.cloud, "sparse");
  EXPECT_FALSE(result.trajectory);
  // 81 x 21 points: x in [-4, -1.1] left only (30 columns), [1.1, 4] right only (30), both 21.
  EXPECT_EQ(result.points, 81u * 21u);
  EXPECT_EQ(result.points_per_combination.at("left"), 30u * 21u);
  EXPECT_EQ(result.points_per_combination.at("right"), 30u * 21u);
  EXPECT_EQ(result.points_per_combination.at("left + right"), 21u * 21u);
  // The coloured cloud and the picture agree point by point (sampled).
  open3d::geometry::PointCloud cloud;
  ASSERT_TRUE(open3d::io::ReadPointCloud((survey / "figures" / "cameras.ply").string(), cloud));
  ASSERT_EQ(cloud.points_.size(), result.points);
  const cv::Mat image = cv::imread((survey / "figures" / "cameras.png").string());
  ASSERT_FALSE(image.empty());
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : cloud.points_) xy.push_back(p.head<2>());
  const TopDownView view(xy, options.image_size_px);
  ASSERT_EQ(image.size(), view.size());
  size_t red = 0, green = 0, yellow = 0, checked = 0;
  for (size_t i = 0; i < cloud.points_.size(); i += 7) {
    const cv::Point2f q = view.pixel(xy[i]);
    const cv::Vec3b pixel =
        image.at<cv::Vec3b>(static_cast<int>(std::lround(q.y)), static_cast<int>(std::lround(q.x)));
    const Eigen::Vector3d c = cloud.colors_[i] * 255.0;  // RGB
    if (pixel[0] < 100 && pixel[1] < 100 && pixel[2] > 200) ++red;
    if (pixel[0] < 100 && pixel[1] > 200 && pixel[2] < 100) ++green;
    if (pixel[0] < 100 && pixel[1] > 200 && pixel[2] > 200) ++yellow;
    // In the legend's corner the box darkens what is below it; elsewhere the colours agree.
    if (q.x > 300 || q.y > 150) {
      EXPECT_NEAR(pixel[2], c.x(), 1.0) << i;
      EXPECT_NEAR(pixel[1], c.y(), 1.0) << i;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100u);
  EXPECT_GT(red, 50u);
  EXPECT_GT(green, 50u);
  EXPECT_GT(yellow, 30u);
}

TEST_F(SyntheticSurvey, TrajectoryFigureWithGroundTruth) {
  FiguresOptions options;
  options.image_size_px = 500;
  const FiguresResult result = writeFigures(Survey(survey_), run_, options);
  EXPECT_TRUE(result.trajectory);
  EXPECT_EQ(result.points_per_combination.size(), 1u);  // one camera
  const cv::Mat figure = cv::imread((survey_ / "figures" / "trajectory.png").string());
  ASSERT_FALSE(figure.empty());
  EXPECT_EQ(std::max(figure.cols, figure.rows), 500);
  // The navigation (green) and the aligned cameras (red) are drawn.
  size_t green = 0, red = 0;
  for (int r = 0; r < figure.rows; ++r) {
    for (int c = 0; c < figure.cols; ++c) {
      const cv::Vec3b p = figure.at<cv::Vec3b>(r, c);
      green += (p[1] > 150 && p[0] < 100 && p[2] < 100) ? 1 : 0;
      red += (p[2] > 180 && p[0] < 100 && p[1] < 100) ? 1 : 0;
    }
  }
  EXPECT_GT(green, 100u);
  EXPECT_GT(red, 50u);
  std::ifstream svg(survey_ / "figures" / "trajectory.svg");
  const std::string text(std::istreambuf_iterator<char>(svg), {});
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("rgb(60,200,60)"), std::string::npos);  // navigation polyline
  // The cloud in the truth's frame: the seabed at depth 5 (and the rock's top at 4).
  open3d::geometry::PointCloud cloud;
  ASSERT_TRUE(open3d::io::ReadPointCloud((survey_ / "figures" / "cameras.ply").string(), cloud));
  for (size_t i = 0; i < cloud.points_.size(); i += 11) {
    const double z = cloud.points_[i].z();
    EXPECT_TRUE(std::abs(z - 5.0) < 1e-5 || (z > 3.99 && z < 5.0)) << z;
  }
}

TEST_F(SyntheticSurvey, FiguresBadInputs) {
  FiguresOptions options;
  options.cloud = "dense";  // fused.ply exists but fused_views.bin does not
  EXPECT_THROW(writeFigures(Survey(survey_), {}, options), StageError);
  options.cloud = "cloudy";
  try {
    writeFigures(Survey(survey_), {}, options);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("cloud = cloudy"), std::string::npos) << e.what();
  }
  fs::remove_all(survey_ / "sparse");
  try {
    writeFigures(Survey(survey_), {}, FiguresOptions{});
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("auv recon sfm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::recon::evaluate
