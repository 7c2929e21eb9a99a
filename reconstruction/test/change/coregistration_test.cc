// Co-registration on stable surfaces: a rolling seabed seen twice, the second time with a new
// block on it and a patch grown by 0.3 m, and moved by a known rigid motion. The motion is
// recovered and the changed places are not what the alignment rests on; plain ICP on every
// point is pulled by them. Surveys that do not overlap, or whose overlap all changed, are
// refused naming the figure.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "auv/recon/change/coregistration.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {
namespace {

double seabed(double x, double y) {
  return 0.4 * std::sin(0.6 * x) * std::cos(0.45 * y) + 0.05 * x;
}

bool onBlock(double x, double y) { return x > 2.0 && x < 5.0 && y > 1.0 && y < 4.0; }
bool onGrowth(double x, double y) { return x > -6.0 && x < -2.0 && y > -6.0 && y < -2.0; }

/// The seabed over [-10, 10]², 5 cm spacing, 5 mm noise (z up here); `changed` adds a 1 m block
/// (its top) and 0.3 m of growth.
std::vector<Eigen::Vector3d> site(bool changed, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<Eigen::Vector3d> points;
  for (double x = -10.0; x <= 10.0; x += 0.05) {
    for (double y = -10.0; y <= 10.0; y += 0.05) {
      double z = seabed(x, y) + noise(rng);
      if (changed && onBlock(x, y)) z += 1.0;
      if (changed && onGrowth(x, y)) z += 0.3;
      points.emplace_back(x, y, z);
    }
  }
  return points;
}

Eigen::Matrix4d motion() {
  Eigen::Affine3d t = Eigen::Translation3d(0.3, -0.2, 0.1) *
                      Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
                      Eigen::AngleAxisd(1.0 * M_PI / 180.0, Eigen::Vector3d::UnitX());
  return t.matrix();
}

std::vector<Eigen::Vector3d> moved(const std::vector<Eigen::Vector3d>& points,
                                   const Eigen::Matrix4d& m) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points)
    out.push_back(m.topLeftCorner<3, 3>() * p + m.topRightCorner<3, 1>());
  return out;
}

/// Rotation (deg) and translation (m) between the found alignment and the true one.
std::pair<double, double> error(const Eigen::Matrix4d& found, const Eigen::Matrix4d& truth) {
  const Eigen::Matrix4d residual = found * truth;  // found undoes truth: identity when exact
  const double angle = Eigen::AngleAxisd(Eigen::Matrix3d(residual.topLeftCorner<3, 3>())).angle();
  return {angle * 180.0 / M_PI, residual.topRightCorner<3, 1>().norm()};
}

TEST(Coregistration, RecoversTheMotionFromTheStableSeabedNotTheChange) {
  const auto before = site(false, 1);
  const auto after_true = site(true, 2);
  const Eigen::Matrix4d truth = motion();
  const auto after = moved(after_true, truth);
  CoregistrationOptions options;
  const CoregistrationResult result =
      coregister(before, after, Eigen::Matrix4d::Identity(), options);
  const auto [degrees, metres] = error(result.transform, truth);
  EXPECT_LT(degrees, 0.05);
  EXPECT_LT(metres, 0.01);
  EXPECT_LT(result.rms_m, 0.01);
  EXPECT_GT(result.overlap, 0.9);
  EXPECT_GT(result.stable_fraction, 0.8);
  EXPECT_LT(result.stable_fraction, 0.99) << "the block and the growth are not stable";
  // The changed places are flagged, the seabed around them is not.
  ASSERT_EQ(result.stable.size(), after.size());
  size_t changed = 0, changed_flagged = 0, seabed_points = 0, seabed_stable = 0;
  for (size_t i = 0; i < after_true.size(); ++i) {
    const double x = after_true[i].x(), y = after_true[i].y();
    const bool near_edge = onBlock(x - 0.3, y) != onBlock(x + 0.3, y) ||
                           onBlock(x, y - 0.3) != onBlock(x, y + 0.3) ||
                           onGrowth(x - 0.3, y) != onGrowth(x + 0.3, y) ||
                           onGrowth(x, y - 0.3) != onGrowth(x, y + 0.3);
    if (near_edge) continue;
    if (onBlock(x, y) || onGrowth(x, y)) {
      ++changed;
      changed_flagged += !result.stable[i];
    } else {
      ++seabed_points;
      seabed_stable += result.stable[i];
    }
  }
  EXPECT_EQ(changed_flagged, changed);
  EXPECT_GT(static_cast<double>(seabed_stable) / seabed_points, 0.99);

  // Plain least squares on every point, even started at the true alignment, is pulled away
  // from it by the change.
  options.rounds = 1;
  options.stable_threshold_m = 10.0;  // the Tukey scale: every residual counts
  const CoregistrationResult plain = coregister(before, after, truth.inverse(), options);
  const auto [plain_degrees, plain_metres] = error(plain.transform, truth);
  std::printf("stable rounds: %.4f deg, %.4f m; plain ICP: %.4f deg, %.4f m\n", degrees, metres,
              plain_degrees, plain_metres);
  EXPECT_GT(plain_metres, 3.0 * metres);
}

TEST(Coregistration, SurveysOfDifferentPlacesAreRefusedNamingTheOverlap) {
  const auto before = site(false, 3);
  Eigen::Matrix4d far = Eigen::Matrix4d::Identity();
  far(0, 3) = 100.0;
  try {
    coregister(before, moved(site(false, 4), far), Eigen::Matrix4d::Identity(),
               CoregistrationOptions());
    FAIL() << "aligned two places 100 m apart";
  } catch (const CoregistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("overlap too little: 0 %"), std::string::npos) << e.what();
  }
}

TEST(Coregistration, AnOverlapThatAllChangedIsRefusedNamingTheStableFraction) {
  const auto before = site(false, 5);
  Eigen::Matrix4d lifted = Eigen::Matrix4d::Identity();
  lifted(2, 3) = 0.5;  // everything 0.5 m higher: within reach, nothing stable
  CoregistrationOptions options;
  options.rounds = 1;
  options.icp_iterations = 1;  // one step cannot bring it down
  options.max_correspondence_m = 1.0;
  try {
    coregister(before, moved(site(false, 6), lifted), Eigen::Matrix4d::Identity(), options);
    FAIL() << "a seabed 0.5 m higher everywhere was called stable";
  } catch (const CoregistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("too little stable surface"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(coregister({}, before, Eigen::Matrix4d::Identity(), options), CoregistrationError);
  options.voxel_m = -1.0;
  EXPECT_THROW(coregister(before, before, Eigen::Matrix4d::Identity(), options), OptionError);
}

}  // namespace
}  // namespace auv::recon::change
