// Tracks, triangulation, resection, relative pose, alignment and bundle adjustment on synthetic
// problems with known answers.
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/sfm/alignment.h"
#include "auv/recon/sfm/bundle_adjustment.h"
#include "auv/recon/sfm/correspondences.h"
#include "auv/recon/sfm/robust_geometry.h"
#include "auv/recon/sfm/triangulation.h"
#include "auv/recon/sfm/undistorted_model.h"
#include "synthetic_scene.h"

namespace auv::recon::sfm {
namespace {

constexpr double kDeg = M_PI / 180.0;

SfmInput tinyInput() {
  SfmInput input;
  input.cameras[1] = scene::Camera::pinhole(1, 100, 100, 100, 100, 50, 50);
  for (uint32_t id = 1; id <= 3; ++id) {
    View v;
    v.id = id;
    v.camera_id = 1;
    v.name = std::to_string(id);
    v.keypoints.assign(5, Eigen::Vector2d(10, 10));
    input.views.push_back(v);
  }
  return input;
}

TEST(Tracks, JoinsMatchesAcrossImagesAndLeavesOutConflictingOnes) {
  SfmInput input = tinyInput();
  // Pair (1, 2), 3 matches, joined first: track A 1:0 - 2:1, track B 1:1 - 2:2, and 1:3 - 2:2
  // conflicts with B (two keypoints of image 1): left out. Pair (2, 3), 2 matches: A gets 3:2
  // through 2:1; C = 2:4 - 3:4.
  input.pairs.push_back({2, 3, {{1, 2}, {4, 4}}, -1, std::nullopt});
  input.pairs.push_back({1, 2, {{0, 1}, {1, 2}, {3, 2}}, -1, std::nullopt});
  input.check();
  const Tracks tracks = Tracks::build(input);
  EXPECT_EQ(tracks.size(), 3u);
  EXPECT_EQ(tracks.stats().conflicting_matches, 1u);
  EXPECT_EQ(tracks.stats().observations, 7u);
  const int64_t a = tracks.trackOf(1, 0);
  ASSERT_NE(a, Tracks::kNoTrack);
  EXPECT_EQ(tracks.trackOf(2, 1), a);
  EXPECT_EQ(tracks.trackOf(3, 2), a);
  EXPECT_EQ(tracks.track(a).size(), 3u);
  const int64_t b = tracks.trackOf(1, 1);
  ASSERT_NE(b, Tracks::kNoTrack);
  EXPECT_EQ(tracks.trackOf(2, 2), b);
  EXPECT_EQ(tracks.track(b).size(), 2u);
  EXPECT_EQ(tracks.trackOf(1, 3), Tracks::kNoTrack);
  EXPECT_NE(tracks.trackOf(3, 4), Tracks::kNoTrack);
  EXPECT_EQ(tracks.trackOf(1, 4), Tracks::kNoTrack);  // never matched
  // No track holds two keypoints of one image, whatever the order of the pairs.
  for (size_t t = 0; t < tracks.size(); ++t) {
    std::set<uint32_t> seen;
    for (const auto& e : tracks.track(t)) EXPECT_TRUE(seen.insert(e.image_id).second);
  }
}

TEST(Tracks, WrongMatchesDoNotChainTracksTogether) {
  // Many random wrong matches over an exhaustive pairing: the true tracks survive.
  testing::SyntheticOptions o;
  o.outlier_ratio = 0.05;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const Tracks tracks = Tracks::build(s.input);
  // Observations that belong to the true point most of their track sees.
  size_t agreeing = 0, observations = 0, longest = 0;
  for (size_t t = 0; t < tracks.size(); ++t) {
    std::map<size_t, size_t> points;
    for (const auto& e : tracks.track(t)) {
      const auto& truth = s.keypoint_point.at(e.image_id);
      auto it = truth.find(e.point2d_idx);
      ++points[it == truth.end() ? SIZE_MAX - e.point2d_idx : it->second];
    }
    size_t best = 0;
    for (const auto& [p, n] : points) best = std::max(best, n);
    agreeing += best;
    observations += tracks.track(t).size();
    longest = std::max(longest, tracks.track(t).size());
  }
  EXPECT_GT(agreeing, 0.95 * observations);
  EXPECT_GT(tracks.size(), 0.9 * s.points.size());
  EXPECT_LE(longest, s.input.views.size());
  EXPECT_GT(tracks.stats().conflicting_matches, 0u);
}

TEST(SfmInput, RejectsBrokenReferencesNamingThem) {
  SfmInput input = tinyInput();
  input.pairs.push_back({1, 2, {{0, 7}}, -1, std::nullopt});
  try {
    input.check();
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pair (1, 2)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(0, 7)"), std::string::npos) << e.what();
  }
  input.pairs = {{2, 2, {}, -1, std::nullopt}};
  EXPECT_THROW(input.check(), std::invalid_argument);
  input.pairs = {{1, 9, {}, -1, std::nullopt}};
  EXPECT_THROW(input.check(), std::invalid_argument);
  input.pairs.clear();
  input.views[0].camera_id = 4;
  EXPECT_THROW(input.check(), std::invalid_argument);
  input = tinyInput();
  input.cameras[1].distortion = {0.1, 0, 0, 0};
  EXPECT_THROW(input.check(), std::invalid_argument);
  input = tinyInput();
  input.views[1].id = 1;
  EXPECT_THROW(input.check(), std::invalid_argument);
}

Matrix34d poseOf(const scene::Image& image) {
  Matrix34d p;
  p.leftCols<3>() = image.rotation();
  p.col(3) = image.t_cw;
  return p;
}

TEST(Triangulation, RecoversPointsFromTwoAndManyViews) {
  testing::SyntheticOptions o;
  o.noise_px = 0;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const scene::Camera& camera = s.input.cameras.at(1);
  // Exact observations: DLT is exact (up to rounding).
  const Eigen::Vector3d x(0.5, -0.3, 10.2);
  std::vector<PosedObservation> obs;
  for (uint32_t id : {1u, 4u, 7u, 10u}) {
    const scene::Image& image = s.truth.at(id);
    const Eigen::Vector3d c = image.toCamera(x);
    obs.push_back({poseOf(image), Eigen::Vector2d(c.x() / c.z(), c.y() / c.z())});
  }
  auto dlt = triangulateDlt({obs[0], obs[1]});
  ASSERT_TRUE(dlt);
  EXPECT_LT((*dlt - x).norm(), 1e-9);
  dlt = triangulateDlt(obs);
  ASSERT_TRUE(dlt);
  EXPECT_LT((*dlt - x).norm(), 1e-9);
  EXPECT_FALSE(triangulateDlt({obs[0]}));

  // Noisy observations (1 px): the refined point is within a few cm at 10 m.
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1.0 / camera.fx);
  for (auto& o2 : obs) o2.normalized += Eigen::Vector2d(noise(rng), noise(rng));
  dlt = triangulateDlt(obs);
  ASSERT_TRUE(dlt);
  const Eigen::Vector3d refined = refineTriangulation(obs, *dlt);
  EXPECT_LT((refined - x).norm(), 0.05);
  EXPECT_GT(depthIn(obs[0].pose_cw, refined), 0);

  // Angle: rays from (0,0,0) and (1,0,0) to (0,0,1) meet at 45 deg.
  EXPECT_NEAR(triangulationAngle({0, 0, 0}, {1, 0, 0}, {0, 0, 1}), 45 * kDeg, 1e-12);
}

TEST(Resection, FindsThePoseWithHalfTheCorrespondencesWrong) {
  testing::SyntheticOptions o;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const uint32_t id = 5;
  const scene::Image& truth = s.truth.at(id);
  const scene::Camera& camera = s.input.cameras.at(truth.camera_id);
  const View& view = s.input.views[id - 1];
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& [k, p] : s.keypoint_point.at(id)) {
    points.push_back(s.points[p]);
    pixels.push_back(view.keypoints[k]);
  }
  const size_t good = points.size();
  std::mt19937 rng(5);
  for (size_t i = 0; i < good; ++i) {  // as many wrong 2D-3D pairs
    points.push_back(s.points[rng() % s.points.size()]);
    pixels.push_back(view.keypoints[rng() % view.keypoints.size()]);
  }
  RobustOptions robust;
  AbsolutePose pose = estimateAbsolutePose(camera, points, pixels, robust);
  ASSERT_TRUE(pose.found);
  EXPECT_GT(pose.inliers.size(), 0.95 * good);
  EXPECT_LT(pose.inliers.size(), 1.1 * good);
  BundleAdjustmentOptions ba;
  ASSERT_TRUE(refineAbsolutePose(camera, points, pixels, pose.inliers, ba, pose.q_cw, pose.t_cw));
  scene::Image estimated = truth;
  estimated.q_cw = pose.q_cw;
  estimated.t_cw = pose.t_cw;
  EXPECT_LT((estimated.center() - truth.center()).norm(), 0.02);  // m, at ~10 m
  EXPECT_LT(estimated.q_cw.angularDistance(truth.q_cw), 0.1 * kDeg);

  // Too few correspondences: no pose, no crash.
  EXPECT_FALSE(
      estimateAbsolutePose(camera, {points[0], points[1]}, {pixels[0], pixels[1]}, robust).found);
}

TEST(RelativePose, MatchesTheTrueMotionOfTwoCameras) {
  testing::SyntheticOptions o;
  o.outlier_ratio = 0;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const uint32_t ia = 1, ib = 7;  // camera 1 at stations 0 and 2
  const View& a = s.input.views[ia - 1];
  const View& b = s.input.views[ib - 1];
  std::vector<Eigen::Vector2d> pa, pb;
  std::map<size_t, uint32_t> in_b;
  for (const auto& [k, p] : s.keypoint_point.at(ib)) in_b[p] = k;
  for (const auto& [k, p] : s.keypoint_point.at(ia)) {
    if (in_b.count(p)) {
      pa.push_back(a.keypoints[k]);
      pb.push_back(b.keypoints[in_b[p]]);
    }
  }
  // 30 % wrong correspondences.
  std::mt19937 rng(9);
  const size_t good = pa.size();
  for (size_t i = 0; i < good * 3 / 10; ++i) {
    pa.push_back(a.keypoints[rng() % a.keypoints.size()]);
    pb.push_back(b.keypoints[rng() % b.keypoints.size()]);
  }
  const RelativePose pose = estimateRelativePose(s.input.cameras.at(a.camera_id),
                                                 s.input.cameras.at(b.camera_id), pa, pb, {});
  ASSERT_TRUE(pose.found);
  EXPECT_GT(pose.inliers.size(), 0.95 * good);
  const scene::Image& ta = s.truth.at(ia);
  const scene::Image& tb = s.truth.at(ib);
  const Eigen::Matrix3d r_true = tb.rotation() * ta.rotation().transpose();
  const Eigen::Vector3d t_true = (tb.t_cw - r_true * ta.t_cw).normalized();
  EXPECT_LT(Eigen::Quaterniond(pose.rotation).angularDistance(Eigen::Quaterniond(r_true)),
            0.2 * kDeg);
  EXPECT_GT(pose.translation.dot(t_true), std::cos(1 * kDeg));
}

TEST(Alignment, RecoversAKnownSimilarityAndRejectsCollinearPoints) {
  std::vector<Eigen::Vector3d> from = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {1, 1, 1}};
  Similarity truth;
  truth.scale = 2.5;
  truth.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  truth.translation = Eigen::Vector3d(4, -1, 2);
  std::vector<Eigen::Vector3d> to;
  for (const auto& x : from) to.push_back(truth.apply(x));
  const auto s = estimateSimilarity(from, to);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->scale, 2.5, 1e-9);
  EXPECT_LT((s->rotation - truth.rotation).norm(), 1e-9);
  EXPECT_LT((s->translation - truth.translation).norm(), 1e-9);
  EXPECT_FALSE(
      estimateSimilarity({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}));
  EXPECT_FALSE(estimateSimilarity({{0, 0, 0}, {1, 0, 0}}, {{0, 0, 0}, {1, 0, 0}}));

  // Poses moved by a similarity come back with zero error.
  testing::SyntheticScene scene = testing::makeSyntheticScene({});
  scene::Reconstruction moved;
  moved.cameras = scene.input.cameras;
  moved.images = scene.truth;
  transformReconstruction(truth, moved);
  const auto errors = poseErrorsAfterAlignment(moved.images, scene.truth);
  ASSERT_TRUE(errors);
  EXPECT_EQ(errors->images, scene.truth.size());
  EXPECT_LT(errors->max_position, 1e-9);
  EXPECT_LT(errors->max_rotation_deg, 1e-5);
  EXPECT_NEAR(errors->alignment.scale, 1 / 2.5, 1e-9);
}

/// The true reconstruction of a synthetic scene (true poses, true points, true tracks).
scene::Reconstruction trueReconstruction(const testing::SyntheticScene& s) {
  scene::Reconstruction rec;
  rec.cameras = s.input.cameras;
  for (const View& view : s.input.views) {
    scene::Image image = s.truth.at(view.id);
    image.points2d = view.keypoints;
    image.point3d_ids.assign(view.keypoints.size(), scene::kNoPoint3D);
    rec.images[view.id] = image;
  }
  for (const auto& [image_id, keypoints] : s.keypoint_point) {
    for (const auto& [k, p] : keypoints) {
      scene::Point3D& point = rec.points[p];
      point.id = p;
      point.xyz = s.points[p];
      point.track.push_back({image_id, k});
      rec.images[image_id].point3d_ids[k] = static_cast<int64_t>(p);
    }
  }
  for (auto it = rec.points.begin(); it != rec.points.end();) {
    if (it->second.track.size() < 2) {
      for (const auto& e : it->second.track) rec.images[e.image_id].point3d_ids[e.point2d_idx] = -1;
      it = rec.points.erase(it);
    } else {
      ++it;
    }
  }
  return rec;
}

TEST(BundleAdjustment, ReducesTheErrorOfAPerturbedProblem) {
  testing::SyntheticOptions o;
  o.noise_px = 0.5;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  scene::Reconstruction rec = trueReconstruction(s);
  rec.checkConsistency();
  const double true_error = rec.meanReprojectionError();
  EXPECT_LT(true_error, 0.8);
  // Perturb: poses by ~5 cm / 0.5 deg, points by ~5 cm; the first image stays as the gauge.
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  for (auto& [id, image] : rec.images) {
    if (id == 1) continue;
    image.q_cw =
        (image.q_cw * Eigen::Quaterniond(Eigen::AngleAxisd(
                          0.5 * kDeg, Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())))
            .normalized();
    image.t_cw += 0.05 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  for (auto& [id, point] : rec.points) point.xyz += 0.05 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  const double perturbed_error = rec.meanReprojectionError();
  EXPECT_GT(perturbed_error, 5.0);

  BundleAdjustmentConfig config;
  for (const auto& [id, image] : rec.images) config.images.insert(id);
  config.constant_images.insert(1);
  BundleAdjustmentOptions options;
  const BundleAdjustmentSummary summary = bundleAdjust(rec, config, options);
  EXPECT_TRUE(summary.usable);
  EXPECT_LT(summary.final_rms_px, summary.initial_rms_px);
  EXPECT_EQ(summary.variable_images, s.truth.size() - 1);
  EXPECT_EQ(summary.constant_pose_images, 1u);
  const double adjusted_error = rec.meanReprojectionError();
  EXPECT_LT(adjusted_error, true_error * 1.02);  // at the noise level (or below: overfit)
  const auto errors = poseErrorsAfterAlignment(rec.images, s.truth);
  ASSERT_TRUE(errors);
  EXPECT_LT(errors->max_position, 0.02);  // m, scene 18 m wide at 10 m
  EXPECT_LT(errors->max_rotation_deg, 0.1);

  // Local problem: one image refined, its neighbours fixed, leaves the others untouched and
  // brings the moved image back (model units: the gauge fixed the scale, not the truth).
  const Eigen::Vector3d before = rec.images.at(2).t_cw, adjusted = rec.images.at(5).center();
  const double extent = (rec.images.at(1).center() - rec.images.at(24).center()).norm();
  rec.images.at(5).t_cw += Eigen::Vector3d(0.02 * extent, 0, 0);
  BundleAdjustmentConfig local;
  local.images = {5};
  local.fix_gauge = false;
  bundleAdjust(rec, local, options);
  EXPECT_EQ(rec.images.at(2).t_cw, before);
  EXPECT_LT((rec.images.at(5).center() - adjusted).norm(), 1e-3 * extent);

  EXPECT_THROW(bundleAdjust(rec, BundleAdjustmentConfig{{999}, {}, {}, {}, true}, options),
               std::invalid_argument);
}

TEST(BundleAdjustment, RobustLossKeepsWrongObservationsFromPullingThePoses) {
  testing::SyntheticOptions o;
  o.noise_px = 0.3;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  scene::Reconstruction rec = trueReconstruction(s);
  // 5 % of observations moved by 30 px.
  std::mt19937 rng(13);
  for (auto& [id, image] : rec.images) {
    for (size_t k = 0; k < image.points2d.size(); ++k) {
      if (image.point3d_ids[k] != scene::kNoPoint3D && rng() % 20 == 0) {
        image.points2d[k] += Eigen::Vector2d(30, -30);
      }
    }
  }
  auto run = [&](LossFunction loss) {
    scene::Reconstruction copy = rec;
    BundleAdjustmentConfig config;
    for (const auto& [id, image] : copy.images) config.images.insert(id);
    BundleAdjustmentOptions options;
    options.loss = loss;
    bundleAdjust(copy, config, options);
    return poseErrorsAfterAlignment(copy.images, s.truth)->mean_position;
  };
  const double robust = run(LossFunction::CAUCHY), plain = run(LossFunction::TRIVIAL);
  EXPECT_LT(robust, 0.01);
  EXPECT_LT(robust, plain);
}

TEST(BundleAdjustment, OptionsRejectBadValuesNamingTheField) {
  BundleAdjustmentOptions options;
  options.loss_scale_px = -1;
  try {
    options.check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("loss_scale_px = -1"), std::string::npos) << e.what();
  }
  EXPECT_EQ(lossFunctionFromName("huber"), LossFunction::HUBER);
  EXPECT_THROW(lossFunctionFromName("L2"), std::invalid_argument);
}

TEST(BundleAdjustment, ALensThatFoldsTheImageHasRunAway) {
  const scene::Camera prior = scene::Camera::pinhole(1, 1000, 750, 800, 800, 499.5, 374.5);
  scene::Camera lens = prior;
  lens.model = scene::CameraModel::OPENCV;
  lens.distortion = {-0.25, 0.08, 0, 0};  // an ordinary barrel lens
  EXPECT_EQ(runawayIntrinsics(lens, prior, 2.0), "");
  lens.distortion = {-1.2, 0.0, 0, 0};  // r (1 - 1.2 r^2) turns back before the corner
  EXPECT_NE(runawayIntrinsics(lens, prior, 2.0).find("radial distortion"), std::string::npos);
  lens.distortion = {1.5, 0.0, 0, 0};  // corners stretched by more than 50 %
  EXPECT_NE(runawayIntrinsics(lens, prior, 2.0).find("radial distortion"), std::string::npos);
}

TEST(UndistortedModel, PinholeCamerasWhoseKeypointsStillSeeTheirPoints) {
  testing::SyntheticOptions o;
  o.cameras = 2;
  o.stations = 3;
  o.distractors = 0;
  o.noise_px = 0;
  o.k1 = -0.2;
  o.k2 = 0.05;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  scene::Reconstruction model;
  model.cameras = s.input.cameras;
  scene::Camera& distorted = model.cameras.at(1);  // camera 2 stays pinhole
  distorted.model = scene::CameraModel::OPENCV;
  distorted.distortion = {o.k1, o.k2, 0, 0};
  for (const View& view : s.input.views) {
    if (view.camera_id == 2) continue;
    scene::Image image = s.truth.at(view.id);
    image.points2d = view.keypoints;
    image.point3d_ids.assign(view.keypoints.size(), scene::kNoPoint3D);
    model.images[image.id] = image;
  }
  const scene::Reconstruction pinhole = undistortedModel(model);
  EXPECT_FALSE(pinhole.cameras.at(1).hasDistortion());
  EXPECT_EQ(pinhole.cameras.at(1).model, scene::CameraModel::PINHOLE);
  EXPECT_EQ(pinhole.cameras.at(2).fx, model.cameras.at(2).fx);  // untouched
  double worst = 0;
  size_t checked = 0;
  for (const auto& [id, image] : pinhole.images) {
    for (const auto& [keypoint, point] : s.keypoint_point.at(id)) {
      const Eigen::Vector2d projected =
          pinhole.cameras.at(1).project(image.toCamera(s.points[point]));
      worst = std::max(worst, (projected - image.points2d[keypoint]).norm());
      ++checked;
    }
  }
  EXPECT_GT(checked, 100u);
  EXPECT_LT(worst, 1e-3);  // px: exact keypoints stay exact in the pinhole images
}

}  // namespace
}  // namespace auv::recon::sfm
