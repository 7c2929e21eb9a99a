// The features and match stages over a survey folder: a real image set (Sceaux castle),
// synthetic SIFT geometry, bad inputs named, earlier outputs intact.
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_h2_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// A textured test image: random blobs of several sizes and grey levels.
cv::Mat texture(int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(90, 110, 100));
  for (int i = 0; i < 900; ++i) {
    cv::circle(image, cv::Point(rng.uniform(0, width), rng.uniform(0, height)), rng.uniform(2, 14),
               cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255)), -1,
               cv::LINE_AA);
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.8);
  return image;
}

void writeCameraYaml(const fs::path& file, int width, int height, double f, double cx, double cy) {
  cv::FileStorage out(file.string(), cv::FileStorage::WRITE);
  out << "image_width" << width << "image_height" << height;
  out << "camera_matrix" << (cv::Mat_<double>(3, 3) << f, 0, cx, 0, f, cy, 0, 0, 1);
  out << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  out << "rms_reprojection_error_px" << 0.0;
}

TEST(Sift, KeypointsFollowAKnownHomographyAndDescriptorsAreRootSift) {
  const cv::Mat image = texture(640, 480, 1);
  cv::Mat h = (cv::Mat_<double>(3, 3) << 0.95, 0.08, 12, -0.06, 1.02, -9, 1e-5, -2e-5, 1);
  cv::Mat warped;
  cv::warpPerspective(image, warped, h, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  SiftOptions options;
  const ImageFeatures f1 = extractSift(image, "a.png", options);
  const ImageFeatures f2 = extractSift(warped, "b.png", options);
  ASSERT_GT(f1.size(), 300u);
  ASSERT_GT(f2.size(), 300u);
  // Sorted by response; RootSIFT rows have an L2 norm of 512 (before rounding).
  for (size_t i = 1; i < f1.size(); ++i) {
    EXPECT_GE(f1.keypoints[i - 1].response, f1.keypoints[i].response);
  }
  for (int r = 0; r < 50; ++r) {
    EXPECT_NEAR(cv::norm(f1.descriptors.row(r), cv::NORM_L2), 512.0, 8.0);
  }
  // Matches map through h within a pixel for the large majority.
  const auto matches = matchDescriptors(f1.descriptors, f2.descriptors, MatchingOptions{});
  ASSERT_GT(matches.size(), 150u);
  int good = 0;
  Eigen::Matrix3d he;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) he(r, c) = h.at<double>(r, c);
  }
  for (const MatchIndices& m : matches) {
    const Eigen::Vector2d p1(f1.keypoints[m.first].x, f1.keypoints[m.first].y);
    const Eigen::Vector2d p2(f2.keypoints[m.second].x, f2.keypoints[m.second].y);
    good += ((he * p1.homogeneous()).hnormalized() - p2).norm() < 1.0 ? 1 : 0;
  }
  EXPECT_GT(good, 0.9 * matches.size());
  // The cap keeps the largest scales by default (as COLMAP), still sorted by response...
  options.max_features = 100;
  const ImageFeatures largest = extractSift(image, "a.png", options);
  ASSERT_EQ(largest.size(), 100u);
  float smallest_kept = largest.keypoints[0].size;
  for (const Keypoint& k : largest.keypoints) smallest_kept = std::min(smallest_kept, k.size);
  size_t larger_in_all = 0;
  for (const Keypoint& k : f1.keypoints) larger_in_all += k.size >= smallest_kept;
  EXPECT_GE(larger_in_all, 100u);
  EXPECT_LE(larger_in_all, 110u);  // ties at the smallest kept size only
  for (size_t i = 1; i < largest.size(); ++i) {
    EXPECT_GE(largest.keypoints[i - 1].response, largest.keypoints[i].response);
  }
  // ... or the strongest responses on request.
  options.keep = "strongest";
  const ImageFeatures strongest = extractSift(image, "a.png", options);
  EXPECT_EQ(strongest.size(), 100u);
  EXPECT_EQ(strongest.keypoints[0].response, f1.keypoints[0].response);
  options.keep = "biggest";
  EXPECT_THROW(options.check(), OptionError);
}

// A cap fit for video frames is too tight for a large photo: it keeps proportionally more.
TEST(Sift, CapGrowsWithTheImageBeyondItsReferenceSize) {
  const cv::Mat image = texture(2000, 1500, 5);  // 3 MP
  SiftOptions options;
  options.max_features = 200;
  options.max_features_megapixels = 1.5;
  EXPECT_EQ(extractSift(image, "a.png", options).size(), 400u);
  options.max_features_megapixels = 3.0;  // up to its reference size: the cap as given
  EXPECT_EQ(extractSift(image, "a.png", options).size(), 200u);
  options.max_features_megapixels = 0;  // fixed
  EXPECT_EQ(extractSift(image, "a.png", options).size(), 200u);
  options.max_features_megapixels = -1;
  EXPECT_THROW(options.check(), OptionError);
}

TEST(Sift, DownscaledDetectionReturnsFullResolutionPixels) {
  const cv::Mat image = texture(1200, 900, 2);
  SiftOptions full, small;
  small.max_image_size = 600;
  const ImageFeatures a = extractSift(image, "a.png", full);
  const ImageFeatures b = extractSift(image, "b.png", small);
  ASSERT_GT(b.size(), 100u);
  EXPECT_EQ(b.width, 1200);
  // Each downscaled keypoint has a full-resolution keypoint within ~1 px (of the 2x image).
  cv::Mat pa(static_cast<int>(a.size()), 2, CV_32F);
  for (size_t i = 0; i < a.size(); ++i) {
    pa.at<float>(static_cast<int>(i), 0) = a.keypoints[i].x;
    pa.at<float>(static_cast<int>(i), 1) = a.keypoints[i].y;
  }
  int near = 0;
  for (const Keypoint& k : b.keypoints) {
    double best = 1e9;
    for (const Keypoint& q : a.keypoints)
      best = std::min<double>(best, std::hypot(q.x - k.x, q.y - k.y));
    near += best < 1.5 ? 1 : 0;
  }
  EXPECT_GT(near, 0.6 * b.size());
  EXPECT_THROW(extractSift(cv::Mat(), "empty.png", full), std::invalid_argument);
}

// Real images: Sceaux castle (11 photos, 2832x2128), downscaled 4x to 708x532 (INTER_AREA) with
// K scaled accordingly, written as a survey's corrected/ folder; then the features and match
// stages as the pipeline runs them (11 images: exhaustive, 55 pairs).
TEST(SurveyStages, SceauxCastleVerifiedPairsHavePlausibleInliers) {
  const fs::path data = fs::path(AUV_RECON_SHARED_DATA) / "sceaux_castle" / "images";
  if (!fs::exists(data)) GTEST_SKIP() << "no " << data << " (shared data absent)";
  const fs::path root = freshFolder("sceaux");
  fs::create_directories(root / "corrected" / "cam");
  constexpr int kDown = 4;
  int width = 0, height = 0;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(data)) {
    if (entry.path().extension() != ".JPG") continue;
    const cv::Mat full = cv::imread(entry.path().string());
    ASSERT_FALSE(full.empty()) << entry.path();
    cv::Mat small;
    cv::resize(full, small, cv::Size(full.cols / kDown, full.rows / kDown), 0, 0, cv::INTER_AREA);
    width = small.cols;
    height = small.rows;
    cv::imwrite((root / "corrected" / "cam" / (entry.path().stem().string() + ".png")).string(),
                small);
    ++count;
  }
  ASSERT_EQ(count, 11);
  // K of K.txt for 2832x2128, scaled with the pixel-centre convention.
  const double s = 1.0 / kDown;
  writeCameraYaml(root / "corrected" / "cam.yaml", width, height, 2905.88 * s,
                  (1416 + 0.5) * s - 0.5, (1064 + 0.5) * s - 0.5);

  const Survey survey(root);
  FeaturesStageOptions extraction;
  extraction.threads = 2;
  const FeaturesStageResult features = runFeaturesStage(survey, extraction);
  EXPECT_EQ(features.images, 11u);
  EXPECT_GT(features.min_features, 1000u);
  MatchStageOptions matching;
  matching.threads = 2;
  const MatchStageResult summary = runMatchStage(survey, matching);
  EXPECT_EQ(summary.candidate_pairs, 55u);
  EXPECT_EQ(summary.essential_pairs, summary.verified_pairs);  // calibrated: essential
  const std::vector<VerifiedPair> pairs = readVerifiedPairs(verifiedPairsFile(root / "features"));
  ASSERT_EQ(pairs.size(), summary.verified_pairs);
  // Consecutive photos of the façade overlap strongly: each is verified with many inliers at a
  // threshold of a few pixels; every image is in some verified pair.
  std::map<std::string, size_t> best;
  for (const VerifiedPair& p : pairs) {
    EXPECT_LT(p.log10_nfa, 0);
    EXPECT_GT(p.threshold_px, 0.2);
    EXPECT_LE(p.threshold_px, 4.0);
    EXPECT_LE(p.numInliers(), p.putative);
    best[p.image1] = std::max(best[p.image1], p.numInliers());
    best[p.image2] = std::max(best[p.image2], p.numInliers());
  }
  EXPECT_EQ(best.size(), 11u);
  for (const auto& [image, inliers] : best) EXPECT_GT(inliers, 150u) << image;
  for (int i = 0; i + 1 < 11; ++i) {
    const std::string a =
        "cam/100_71" + std::string(i < 10 ? "0" : "") + std::to_string(i) + ".png";
    const std::string b =
        "cam/100_71" + std::string(i + 1 < 10 ? "0" : "") + std::to_string(i + 1) + ".png";
    bool found = false;
    for (const VerifiedPair& p : pairs) found = found || (p.image1 == a && p.image2 == b);
    EXPECT_TRUE(found) << a << " - " << b << " not verified";
  }
  // The report has both sections.
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["features"]["images"], 11);
  EXPECT_EQ(report["stages"]["match"]["verified_pairs"], summary.verified_pairs);
  fs::remove_all(root);
}

TEST(SurveyStages, MissingCorrectedFolderIsNamed) {
  const fs::path root = freshFolder("no_corrected");
  try {
    runFeaturesStage(Survey(root), FeaturesStageOptions{});
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find((root / "corrected").string()), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("auv recon correct"), std::string::npos) << e.what();
  }
  try {
    runMatchStage(Survey(root), MatchStageOptions{});
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("auv recon features"), std::string::npos) << e.what();
  }
  fs::remove_all(root);
}

TEST(SurveyStages, UnreadableImageIsNamedAndEarlierFeaturesStayIntact) {
  const fs::path root = freshFolder("bad_image");
  fs::create_directories(root / "corrected" / "left");
  cv::imwrite((root / "corrected" / "left" / "left_0001_000001.png").string(),
              texture(320, 240, 3));
  cv::imwrite((root / "corrected" / "left" / "left_0001_000002.png").string(),
              texture(320, 240, 4));
  const Survey survey(root);
  FeaturesStageOptions options;
  options.threads = 1;
  ASSERT_EQ(runFeaturesStage(survey, options).images, 2u);
  const std::string index_before = [&] {
    std::ifstream in(root / "features" / "index.csv");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  // A corrupt PNG joins the folder: the stage fails naming it, features/ is untouched.
  std::ofstream(root / "corrected" / "left" / "left_0001_000003.png") << "\x89PNG garbage";
  try {
    runFeaturesStage(survey, options);
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("left_0001_000003.png"), std::string::npos) << e.what();
  }
  std::ifstream in(root / "features" / "index.csv");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), index_before);
  // No staging folder left behind.
  for (const auto& entry : fs::directory_iterator(root)) {
    EXPECT_EQ(entry.path().filename().string().find(".features.staging"), std::string::npos);
  }
  fs::remove_all(root);
}

TEST(SurveyStages, UncalibratedCamerasUseTheFundamentalMatrix) {
  // A planar textured scene seen by a moving camera (homographies): no corrected/<camera>.yaml.
  const fs::path root = freshFolder("uncalibrated");
  fs::create_directories(root / "corrected" / "cam");
  const cv::Mat base = texture(640, 480, 5);
  for (int i = 0; i < 3; ++i) {
    cv::Mat h =
        (cv::Mat_<double>(3, 3) << 1, 0.02 * i, 8.0 * i, -0.01 * i, 1, 5.0 * i, 2e-5 * i, 0, 1);
    cv::Mat view;
    cv::warpPerspective(base, view, h, base.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    cv::imwrite((root / "corrected" / "cam" / ("cam_" + std::to_string(i) + ".png")).string(),
                view);
  }
  const Survey survey(root);
  FeaturesStageOptions extraction;
  extraction.threads = 1;
  runFeaturesStage(survey, extraction);
  MatchStageOptions matching;
  matching.threads = 1;
  const MatchStageResult summary = runMatchStage(survey, matching);
  EXPECT_EQ(summary.candidate_pairs, 3u);
  EXPECT_EQ(summary.verified_pairs, 3u);
  EXPECT_EQ(summary.fundamental_pairs, 3u);
  for (const VerifiedPair& p : readVerifiedPairs(verifiedPairsFile(root / "features"))) {
    EXPECT_EQ(p.kind, GeometryKind::FUNDAMENTAL);
    // A planar scene: the homography explains (nearly) all the inliers.
    EXPECT_GT(p.homography_inliers, 0.8 * p.numInliers());
  }
  // A distorted calibration is refused by name.
  writeCameraYaml(root / "corrected" / "cam.yaml", 640, 480, 500, 320, 240);
  {
    cv::FileStorage out((root / "corrected" / "cam.yaml").string(), cv::FileStorage::WRITE);
    out << "image_width" << 640 << "image_height" << 480;
    out << "camera_matrix" << (cv::Mat_<double>(3, 3) << 500, 0, 320, 0, 500, 240, 0, 0, 1);
    out << "distortion_coefficients" << (cv::Mat_<double>(1, 5) << -0.2, 0.05, 0, 0, 0);
  }
  try {
    runMatchStage(survey, matching);
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("cam.yaml: non-zero distortion_coefficients"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(root);
}

// A pair whose putative matches are chance (random positions): with hopeless_exit it stops at
// the samples that would have found a model of min_inliers inliers, without it it draws them
// all; either way it does not verify.
TEST(VerifyPair, AChancePairStopsAtTheMinInliersBound) {
  std::mt19937 random(3);
  std::uniform_real_distribution<float> x(0, 1352), y(0, 1014);
  ImageFeatures a, b;
  a.image = "cam/a.png";
  b.image = "cam/b.png";
  a.width = b.width = 1352;
  a.height = b.height = 1014;
  PairGeometryInput input;
  for (uint32_t i = 0; i < 60; ++i) {
    a.keypoints.push_back({x(random), y(random)});
    b.keypoints.push_back({x(random), y(random)});
    input.putative.emplace_back(i, i);
  }
  const scene::Camera camera = scene::Camera::pinhole(1, 1352, 1014, 682, 682, 675.5, 506.5);
  input.features1 = &a;
  input.features2 = &b;
  input.camera1 = input.camera2 = &camera;
  VerificationOptions options;
  PairVerification bounded, full;
  EXPECT_TRUE(verifyPair(input, options, &bounded).inliers.empty());
  EXPECT_TRUE(bounded.hopeless);
  EXPECT_EQ(bounded.iterations, 146);  // log(0.01) / log(1 - (30/60)^5) = 145.05
  options.hopeless_exit = false;
  EXPECT_TRUE(verifyPair(input, options, &full).inliers.empty());
  EXPECT_FALSE(full.hopeless);
  EXPECT_EQ(full.iterations, 4096 - 409);  // no meaningful model: no reserve drawn
}

}  // namespace
}  // namespace auv::recon::features
