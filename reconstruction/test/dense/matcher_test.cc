// Depth maps of synthetic scenes against their true depth.
#include "auv/recon/dense/matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "auv/recon/common/stage_error.h"
#include "synthetic_scene.h"

namespace auv::recon::dense {
namespace {

using testing::Scene;

struct DepthErrors {
  double median_relative = 1;   ///< over valid depths
  double valid_fraction = 0;    ///< of the pixels `mask` selects
  double outlier_fraction = 1;  ///< valid depths more than 5 % off
};

DepthErrors compare(const cv::Mat& depth, const cv::Mat& truth, const cv::Mat& mask) {
  std::vector<double> errors;
  size_t selected = 0, valid = 0, outliers = 0;
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      if (!mask.at<uint8_t>(y, x)) continue;
      ++selected;
      const double d = depth.at<float>(y, x), t = truth.at<float>(y, x);
      if (d <= 0) continue;
      ++valid;
      const double e = std::abs(d - t) / t;
      errors.push_back(e);
      if (e > 0.05) ++outliers;
    }
  }
  DepthErrors result;
  if (!errors.empty()) {
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    result.median_relative = errors[errors.size() / 2];
    result.outlier_fraction = static_cast<double>(outliers) / valid;
  }
  result.valid_fraction = selected ? static_cast<double>(valid) / selected : 0;
  return result;
}

/// Pixels of the master that at least `min_views` neighbours see (true geometry, no
/// occlusion test beyond the depth check), away from the image border by `border` px.
cv::Mat seenByNeighbours(const View& master, const cv::Mat& truth, const std::vector<View>& others,
                         const std::vector<cv::Mat>& other_depths, int min_views, int border) {
  cv::Mat mask(truth.size(), CV_8U, cv::Scalar(0));
  for (int y = border; y < truth.rows - border; ++y) {
    for (int x = border; x < truth.cols - border; ++x) {
      const double d = truth.at<float>(y, x);
      if (d <= 0) continue;
      const Eigen::Vector3d world = master.backProject(x, y, d);
      int seen = 0;
      for (size_t k = 0; k < others.size(); ++k) {
        const Eigen::Vector3d c = others[k].toCamera(world);
        const Eigen::Vector2d p = others[k].project(c);
        const int px = static_cast<int>(std::lround(p.x())),
                  py = static_cast<int>(std::lround(p.y()));
        if (c.z() <= 0 || px < border || py < border || px >= truth.cols - border ||
            py >= truth.rows - border) {
          continue;
        }
        if (std::abs(other_depths[k].at<float>(py, px) - c.z()) < 0.01 * c.z()) ++seen;
      }
      mask.at<uint8_t>(y, x) = seen >= min_views ? 255 : 0;
    }
  }
  return mask;
}

class MatcherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    views_ = testing::gridViews(3, 3, 0.35, 4.0);
    for (View& view : views_) depths_.push_back(testing::render(scene_, view));
    master_ = views_[4];  // the centre of the 3x3 grid
    for (size_t i = 0; i < views_.size(); ++i) {
      if (i == 4 || neighbours_.size() == 4) continue;
      if (i == 1 || i == 3 || i == 5 || i == 7) {
        neighbours_.push_back(views_[i]);
        neighbour_depths_.push_back(depths_[i]);
      }
    }
  }
  Scene scene_;
  std::vector<View> views_;
  std::vector<cv::Mat> depths_;
  View master_;
  std::vector<View> neighbours_;
  std::vector<cv::Mat> neighbour_depths_;
};

// Tolerances: median relative depth error < 1 %, > 90 % of the pixels two neighbours see
// (4 px from the borders) get a depth, < 2 % of the depths are more than 5 % off.
TEST_F(MatcherTest, DepthOfPlaneAndSphereWithinTolerance) {
  MatcherOptions options;
  const DepthMapResult result = computeDepthMap(master_, neighbours_, 2.5, 5.0, options);
  const cv::Mat mask = seenByNeighbours(master_, depths_[4], neighbours_, neighbour_depths_, 2, 4);
  const DepthErrors errors = compare(result.depth, depths_[4], mask);
  std::printf(
      "levels %zu, labels coarsest %d finest %d; median error %.4f %%, valid %.1f %%, "
      "outliers %.2f %%, cost %.2f s, sgm %.2f s\n",
      result.labels_per_level.size(), result.labels_per_level.front(),
      result.labels_per_level.back(), 100 * errors.median_relative, 100 * errors.valid_fraction,
      100 * errors.outlier_fraction, result.seconds_cost, result.seconds_sgm);
  EXPECT_GT(result.labels_per_level.size(), 1u) << "coarse to fine over several levels";
  EXPECT_LT(errors.median_relative, 0.01);
  EXPECT_GT(errors.valid_fraction, 0.90);
  EXPECT_LT(errors.outlier_fraction, 0.02);
  EXPECT_EQ(result.depth.size(), cv::Size(master_.width, master_.height));
}

}  // namespace
}  // namespace auv::recon::dense

namespace auv::recon::dense {
namespace {

TEST_F(MatcherTest, BadInputIsRejectedNamingTheImage) {
  const MatcherOptions options;
  try {
    computeDepthMap(master_, neighbours_, 5.0, 2.5, options);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(master_.name), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("depth range"), std::string::npos) << e.what();
  }
  EXPECT_THROW(computeDepthMap(master_, {}, 2.5, 5.0, options), std::invalid_argument);
  View unloaded = neighbours_[0];
  unloaded.grey.release();
  EXPECT_THROW(computeDepthMap(master_, {unloaded}, 2.5, 5.0, options), std::invalid_argument);
  MatcherOptions bad;
  bad.directions = 6;
  EXPECT_THROW(computeDepthMap(master_, neighbours_, 2.5, 5.0, bad), OptionError);
}

// Where no neighbour sees the master (a master looking elsewhere), no depth is invented.
TEST_F(MatcherTest, NoDepthWhereNoNeighbourSees) {
  View elsewhere = testing::downwardView(20, {40, 0, 4}, 240, 180, 220);
  testing::render(scene_, elsewhere);
  const DepthMapResult result = computeDepthMap(master_, {elsewhere}, 2.5, 5.0, MatcherOptions());
  EXPECT_LT(result.valid_pixels, result.depth.total() / 100);
}

}  // namespace
}  // namespace auv::recon::dense
