// Similarity alignment from camera poses: known similarities recovered with noise and outliers,
// a straight trajectory, degenerate and bad inputs.
#include "auv/recon/evaluate/alignment.h"

#include <gtest/gtest.h>

#include <random>

#include "auv/recon/common/stage_error.h"
#include "synthetic_scene.h"

namespace auv::recon::evaluate {
namespace {

/// Pose pairs: true cameras at `centers` with random orientations; the estimates are the truth
/// mapped by the inverse of `truth_from_rec`, plus noise (m in the truth's units, rad).
std::vector<PosePair> makePairs(const std::vector<Eigen::Vector3d>& centers,
                                const Similarity& truth_from_rec, double position_noise,
                                double angle_noise, std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Similarity rec_from_truth = truth_from_rec.inverse();
  std::vector<PosePair> pairs;
  for (size_t i = 0; i < centers.size(); ++i) {
    PosePair p;
    p.name = "cam/" + std::to_string(i);
    p.center_truth = centers[i];
    p.rotation_truth_cw =
        Eigen::AngleAxisd(0.3 * gauss(rng), Eigen::Vector3d::UnitX()).toRotationMatrix() *
        Eigen::AngleAxisd(3.0 * gauss(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d noisy =
        centers[i] + position_noise * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    p.center_estimate = rec_from_truth.apply(noisy);
    const Eigen::Matrix3d perturbation =
        Eigen::AngleAxisd(angle_noise * gauss(rng),
                          Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized())
            .toRotationMatrix();
    // R_truth = R_est R^T  =>  R_est = R_truth R.
    p.rotation_estimate_cw = perturbation * p.rotation_truth_cw * truth_from_rec.rotation;
    pairs.push_back(p);
  }
  return pairs;
}

void expectNear(const Similarity& a, const Similarity& b, double scale_tol, double angle_tol_deg,
                double translation_tol) {
  EXPECT_NEAR(a.scale, b.scale, scale_tol * b.scale);
  const double angle = Eigen::AngleAxisd(a.rotation * b.rotation.transpose()).angle() * 180 / M_PI;
  EXPECT_LT(angle, angle_tol_deg);
  EXPECT_LT((a.translation - b.translation).norm(), translation_tol);
}

TEST(Alignment, RecoversAKnownSimilarityExactly) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  std::vector<Eigen::Vector3d> centers;
  for (int i = 0; i < 30; ++i) centers.emplace_back(u(rng), u(rng), 0.2 * u(rng));
  const Similarity truth = testing::knownSimilarity();
  const auto pairs = makePairs(centers, truth, 0.0, 0.0, rng);
  const AlignmentResult result = alignToTruth(pairs, AlignmentOptions{});
  ASSERT_EQ(result.status, AlignmentStatus::SUCCESS) << result.message;
  expectNear(result.similarity, truth, 1e-9, 1e-6, 1e-7);
  EXPECT_EQ(result.num_inliers, pairs.size());
  const PoseErrors errors = poseErrors(pairs, result.similarity);
  EXPECT_LT(errors.max_position_m, 1e-7);
  EXPECT_LT(errors.max_rotation_deg, 1e-5);
}

TEST(Alignment, NoiseAndOutliersOnAStraightTrajectory) {
  // A canyon traverse: centres along a line at constant depth (only the 0.16 m between the two
  // down cameras off it). Centres alone cannot fix the roll about the line; axis points can.
  std::mt19937_64 rng(5);
  std::vector<Eigen::Vector3d> centers;
  for (int i = 0; i < 60; ++i) {
    centers.emplace_back(-15.0 + 0.5 * i, (i % 2 ? 0.08 : -0.08), 3.0);
  }
  const Similarity truth = testing::knownSimilarity();
  auto pairs = makePairs(centers, truth, 0.01, 0.002, rng);  // 1 cm, 0.1 deg noise
  // 15% of the images registered wrongly: far off and turned.
  for (size_t i = 0; i < pairs.size(); i += 7) {
    pairs[i].center_estimate += Eigen::Vector3d(2.0, -1.0, 3.0);
    pairs[i].rotation_estimate_cw =
        Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()).toRotationMatrix() *
        pairs[i].rotation_estimate_cw;
  }
  const AlignmentResult result = alignToTruth(pairs, AlignmentOptions{});
  ASSERT_EQ(result.status, AlignmentStatus::SUCCESS) << result.message;
  expectNear(result.similarity, truth, 0.005, 0.5, 0.1);
  for (size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(result.inliers[i], i % 7 != 0) << "image " << i;
  }
  const PoseErrors errors = poseErrors(pairs, result.similarity);
  EXPECT_LT(errors.median_position_m, 0.03);  // the 1 cm noise, x sqrt(3) and a margin
  EXPECT_GT(errors.max_position_m, 1.0);      // the outliers stay visible in the errors
}

TEST(Alignment, CentresOnALineAloneAreDegenerate) {
  std::mt19937_64 rng(7);
  std::vector<Eigen::Vector3d> centers;
  for (int i = 0; i < 10; ++i) centers.emplace_back(i, 0, 3);
  const auto pairs = makePairs(centers, testing::knownSimilarity(), 0, 0, rng);
  AlignmentOptions options;
  options.axis_length_m = 0;
  const AlignmentResult result = alignToTruth(pairs, options);
  EXPECT_EQ(result.status, AlignmentStatus::DEGENERATE);
  EXPECT_NE(result.message.find("collinear"), std::string::npos) << result.message;
  // With axis points the same poses align.
  EXPECT_EQ(alignToTruth(pairs, AlignmentOptions{}).status, AlignmentStatus::SUCCESS);
}

TEST(Alignment, TooFewImagesAndBadOptions) {
  std::mt19937_64 rng(9);
  const auto pairs = makePairs({{0, 0, 0}, {1, 0, 0}}, testing::knownSimilarity(), 0, 0, rng);
  const AlignmentResult result = alignToTruth(pairs, AlignmentOptions{});
  EXPECT_EQ(result.status, AlignmentStatus::TOO_FEW_IMAGES);
  EXPECT_NE(result.message.find("2 images"), std::string::npos) << result.message;

  AlignmentOptions bad;
  bad.axis_length_m = -1;
  try {
    alignToTruth(pairs, bad);
    FAIL() << "negative axis length accepted";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("axis_length_m = -1"), std::string::npos) << e.what();
  }
  bad = AlignmentOptions{};
  bad.min_images = 2;
  EXPECT_THROW(bad.check(), OptionError);
}

TEST(Alignment, SimilarityInverseAndMatrix) {
  const Similarity s = testing::knownSimilarity();
  const Eigen::Vector3d x(1, 2, 3);
  EXPECT_LT((s.inverse().apply(s.apply(x)) - x).norm(), 1e-12);
  const Eigen::Vector4d h = s.matrix() * x.homogeneous();
  EXPECT_LT((h.head<3>() - s.apply(x)).norm(), 1e-12);
}

}  // namespace
}  // namespace auv::recon::evaluate
