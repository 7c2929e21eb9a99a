// Figures 19 and 20: colours of camera combinations, top-down drawing at known places, the
// per-camera figure of a two-camera survey, the trajectory figure with ground truth, bad inputs.
#include "auv/recon/evaluate/figures.h"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>

#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

TEST(TopDown, LongStraightTraverseIsFramedWithReliefBesideIt) {
  // An 18 m traverse due north, as the canyon survey: 15 % (2.7 m) < 4 m of margin, so 4 m on
  // each side; 26 m north, 8 m east widened to half of 26 m: 13 m, centred on the path.
  std::vector<Eigen::Vector2d> path;
  for (int i = 0; i <= 18; ++i) path.emplace_back(10.0 + i, -2.0);
  TopDownFraming framing;
  framing.margin = 0.15;
  framing.min_margin_m = 4.0;
  framing.min_aspect = 0.5;
  const TopDownView view(path, 1600, framing);
  EXPECT_EQ(view.size(), cv::Size(800, 1600));
  EXPECT_NEAR(view.pixelsPerMetre(), 1600 / 26.0, 1e-9);
  EXPECT_NEAR(view.pixel({19, -2}).x, 400, 1e-3);  // centred
  EXPECT_NEAR(view.pixel({19, -2}).y, 800, 1e-3);
  EXPECT_NEAR(view.pixel({28, -2}).y, 4 * 1600 / 26.0, 1e-3);  // 4 m above the north end
  EXPECT_NEAR(view.pixel({19, -8.5}).x, 0, 1e-3);              // 6.5 m either side
  EXPECT_NEAR(view.pixel({19, 4.5}).x, 800, 1e-3);
  // An east-west traverse: the same, turned.
  std::vector<Eigen::Vector2d> across;
  for (const auto& p : path) across.emplace_back(p.y(), p.x());
  EXPECT_EQ(TopDownView(across, 1600, framing).size(), cv::Size(1600, 800));
  // Room for a legend: the same scale, more of the world about the centre.
  framing.min_size_px = cv::Size(1000, 100);
  const TopDownView wide(path, 1600, framing);
  EXPECT_EQ(wide.size(), cv::Size(1000, 1600));
  EXPECT_NEAR(wide.pixelsPerMetre(), view.pixelsPerMetre(), 1e-9);
  EXPECT_NEAR(wide.pixel({19, -2}).x, 500, 1e-3);
  // Without framing the old behaviour: the path's own strip.
  EXPECT_EQ(TopDownView(path, 1600).size().height, 1600);
  EXPECT_LT(TopDownView(path, 1600).size().width, 10);
  // Bad framings.
  TopDownFraming bad;
  bad.min_aspect = 1.5;
  EXPECT_THROW(TopDownView(path, 1600, bad), std::invalid_argument);
  bad = TopDownFraming{};
  bad.min_margin_m = -1;
  EXPECT_THROW(TopDownView(path, 1600, bad), std::invalid_argument);
}

/// The legend box drawLegend left on `image`, found as the region darkened against the
/// undarkened strip left of and above it (the box starts 8 px from the corner): its right end
/// along row 10 (against row 3) and its bottom along column 10 (against column 3). Empty when
/// there is no darkened run from the corner.
cv::Rect observedLegendBox(const cv::Mat& image) {
  auto darker = [&](int r, int c, int r0, int c0) {
    const cv::Vec3b p = image.at<cv::Vec3b>(r, c), q = image.at<cv::Vec3b>(r0, c0);
    for (int k = 0; k < 3; ++k) {
      if (q[k] < 10 || p[k] > 0.5 * q[k]) return false;
    }
    return true;
  };
  int right = 8, bottom = 8;
  while (right < image.cols && darker(10, right, 3, right)) ++right;
  while (bottom < image.rows && darker(bottom, 10, bottom, 3)) ++bottom;
  return cv::Rect(8, 8, right - 8, bottom - 8);
}

/// Checks that the legend box lies inside `image` with undarkened image right of it and that
/// every bright (text) pixel of its rows lies inside it.
void expectLegendInside(const cv::Mat& image) {
  const cv::Rect box = observedLegendBox(image);
  ASSERT_GT(box.width, 50);
  ASSERT_GT(box.height, 30);
  EXPECT_LE(box.br().x, image.cols - 4) << "legend box reaches the right edge";
  EXPECT_LE(box.br().y, image.rows - 4);
  int rightmost_text = 0;
  for (int r = box.y; r < box.br().y; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b p = image.at<cv::Vec3b>(r, c);
      if (p[0] > 200 && p[1] > 200 && p[2] > 200) rightmost_text = std::max(rightmost_text, c);
    }
  }
  EXPECT_GT(rightmost_text, box.x + box.width / 2);  // there is text
  EXPECT_LT(rightmost_text, box.br().x);
}

TEST(Legend, MeasuredTextFitsItsBoxAndTheImage) {
  const std::vector<LegendEntry> entries{{{60, 200, 60}, "vehicle navigation (dead reckoning)"},
                                         {{50, 50, 230}, "SfM cameras (aligned to the truth)"},
                                         {{230, 230, 230}, "true trajectory"}};
  for (int size_px : {200, 1600, 6000}) {
    const double font = legendFontScale(size_px);
    const cv::Size need = legendImageSize(entries, font);
    int baseline = 0;
    const int text =
        cv::getTextSize(entries[0].second, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width;
    EXPECT_GT(need.width, text + 8) << size_px;
    cv::Mat image(need, CV_8UC3, cv::Scalar(100, 100, 100));
    const cv::Rect box = drawLegend(image, entries, 10.0, font);
    EXPECT_EQ(box & cv::Rect(0, 0, image.cols, image.rows), box) << size_px;
    EXPECT_GE(box.width, text) << size_px;
    expectLegendInside(image);
    // One pixel too narrow or too low: refused, not cut.
    cv::Mat narrow(need - cv::Size(1, 0), CV_8UC3), low(need - cv::Size(0, 1), CV_8UC3);
    EXPECT_THROW(drawLegend(narrow, entries, 10.0, font), std::invalid_argument) << size_px;
    EXPECT_THROW(drawLegend(low, entries, 10.0, font), std::invalid_argument) << size_px;
  }
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
  const FiguresStageResult result = writeFigures(Survey(survey), {}, options);
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
  // The cloud is a 8.8 x 2.2 m strip (150 px wide at 600 px): the image is widened for the
  // legend, whose box and text lie inside it.
  const std::vector<LegendEntry> legend{{combinationColor(0b01, 2), "left  37.0 %"},
                                        {combinationColor(0b10, 2), "right  37.0 %"},
                                        {combinationColor(0b11, 2), "left + right  25.9 %"}};
  const double font = legendFontScale(options.image_size_px);
  TopDownFraming framing;
  framing.min_size_px = legendImageSize(legend, font);
  EXPECT_GT(framing.min_size_px.width, 150);
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : cloud.points_) xy.push_back(p.head<2>());
  const TopDownView view(xy, options.image_size_px, framing);
  ASSERT_EQ(image.size(), view.size());
  EXPECT_EQ(image.rows, 600);
  expectLegendInside(image);
  const cv::Rect legend_box = observedLegendBox(image);
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
    if (!legend_box.contains(cv::Point(static_cast<int>(q.x), static_cast<int>(q.y)))) {
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
  const FiguresStageResult result = writeFigures(Survey(survey_), run_, options);
  EXPECT_TRUE(result.trajectory);
  EXPECT_EQ(result.points_per_combination.size(), 1u);  // one camera
  const cv::Mat figure = cv::imread((survey_ / "figures" / "trajectory.png").string());
  ASSERT_FALSE(figure.empty());
  EXPECT_EQ(std::max(figure.cols, figure.rows), 500);
  // The path runs 6 m north and sways 0.3 m: the figure is still at least half as wide as
  // tall, the legend inside.
  EXPECT_GE(2 * figure.cols, figure.rows);
  expectLegendInside(figure);
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
  // At least 4 m of relief around the cameras (keyframes from x = -3 to 3 m north, dots of
  // radius 3 px; 3.8 m for the dots' size): their pixel span gives the scale; the world plane
  // reaches 6 m either side.
  cv::Mat red_mask;
  cv::inRange(figure, cv::Scalar(0, 0, 181), cv::Scalar(99, 99, 255), red_mask);
  red_mask(observedLegendBox(figure)).setTo(0);  // its red swatch
  const cv::Rect cameras = cv::boundingRect(red_mask);
  const double pixels_per_metre = (cameras.height - 6) / 6.0;
  const int margin = static_cast<int>(3.8 * pixels_per_metre);  // dots and anti-aliasing
  EXPECT_GE(cameras.x, margin);
  EXPECT_GE(figure.cols - cameras.br().x, margin);
  EXPECT_GE(cameras.y, margin);
  EXPECT_GE(figure.rows - cameras.br().y, margin);
  const cv::Vec3b beside = figure.at<cv::Vec3b>(cameras.y + cameras.height / 2, cameras.x - margin);
  EXPECT_NEAR(beside[0], 150 - 11 * 5, 2);  // the seabed's relief at depth 5, not background
  // The SVG: the same size, its legend text (textLength) inside.
  std::ifstream svg(survey_ / "figures" / "trajectory.svg");
  const std::string text(std::istreambuf_iterator<char>(svg), {});
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("rgb(60,200,60)"), std::string::npos);  // navigation polyline
  EXPECT_NE(text.find("width=\"" + std::to_string(figure.cols) + "\" height=\"" +
                      std::to_string(figure.rows) + "\""),
            std::string::npos);
  auto attribute = [&](size_t from, const std::string& name) {
    const size_t at = text.find(" " + name + "=\"", from);
    return at == std::string::npos ? -1.0 : std::stod(text.substr(at + name.size() + 3));
  };
  int labels = 0;
  for (size_t at = text.find("<text"); at != std::string::npos; at = text.find("<text", at + 1)) {
    const double x = attribute(at, "x"), length = attribute(at, "textLength");
    EXPECT_GT(length, 0);
    EXPECT_LE(x + length, figure.cols - 8) << text.substr(at, 200);
    ++labels;
  }
  EXPECT_EQ(labels, 4);  // three legend rows and the scale bar
  EXPECT_NE(text.find("vehicle navigation (dead reckoning)"), std::string::npos);
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
