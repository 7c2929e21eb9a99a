// Incremental SfM on synthetic multi-camera scenes: every image registered, poses within
// tolerance of the truth after a similarity alignment; expected failures as status values.
#include <gtest/gtest.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/sfm/alignment.h"
#include "auv/recon/sfm/incremental_mapper.h"
#include "synthetic_scene.h"

namespace auv::recon::sfm {
namespace {

TEST(IncrementalMapper, ImagesOfASeparateGroupSayTheyAreNotConnected) {
  testing::SyntheticOptions o;
  o.cameras = 3;
  o.stations = 8;
  testing::SyntheticScene s = testing::makeSyntheticScene(o);
  // The third camera's views matched only one another (as a camera looking into murk does).
  std::map<uint32_t, uint32_t> camera_of;
  for (const View& view : s.input.views) camera_of[view.id] = view.camera_id;
  const uint32_t third = camera_of.rbegin()->second;
  std::vector<ViewPair> kept;
  for (const ViewPair& pair : s.input.pairs) {
    if ((camera_of[pair.image_a] == third) == (camera_of[pair.image_b] == third))
      kept.push_back(pair);
  }
  s.input.pairs = kept;
  IncrementalMapper mapper(s.input, MapperOptions());
  const MapperResult result = mapper.run(nullptr, nullptr);
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  ASSERT_EQ(result.unregistered.size(), 8u);
  for (uint32_t id : result.unregistered) {
    EXPECT_EQ(camera_of[id], third);
    const std::string& why = result.unregistered_reasons.at(id);
    EXPECT_NE(why.find("not connected to the model"), std::string::npos) << why;
    EXPECT_NE(why.find("only to 7 other"), std::string::npos) << why;
  }
}

TEST(IncrementalMapper, ReconstructsAThreeCameraRigWithWrongMatches) {
  testing::SyntheticOptions o;
  o.cameras = 3;
  o.stations = 8;
  o.noise_px = 0.5;
  o.outlier_ratio = 0.03;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  ASSERT_EQ(s.input.views.size(), 24u);
  MapperOptions options;
  IncrementalMapper mapper(s.input, options);
  std::vector<std::string> log;
  const MapperResult result =
      mapper.run(nullptr, [&](const std::string& line) { log.push_back(line); });
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  const scene::Reconstruction& rec = result.reconstruction;
  EXPECT_EQ(rec.images.size(), 24u);
  EXPECT_TRUE(result.unregistered.empty());
  EXPECT_EQ(rec.cameras.size(), 3u);
  rec.checkConsistency();
  EXPECT_LT(rec.meanReprojectionError(), 0.8);  // px: noise 0.5 px -> ~0.6 px expected
  EXPECT_GT(rec.points.size(), 0.8 * s.points.size());
  EXPECT_GT(rec.meanTrackLength(), 4.0);
  EXPECT_GT(result.local_bas, 0u);
  const MapperTimings& tm = result.timings;
  EXPECT_LE(tm.tracks + tm.initial_pair + tm.registration + tm.triangulation + tm.local_ba +
                tm.global_ba + tm.filtering,
            tm.total * 1.001);
  EXPECT_GT(result.global_bas, 0u);
  EXPECT_FALSE(log.empty());

  const auto errors = poseErrorsAfterAlignment(rec.images, s.truth);
  ASSERT_TRUE(errors);
  EXPECT_EQ(errors->images, 24u);
  EXPECT_LT(errors->max_position, 0.03);  // m (scene 18 m wide, ~10 m away)
  EXPECT_LT(errors->max_rotation_deg, 0.2);

  // Every point is where it should be: mapped through the alignment, near the true point of
  // its track (the tracks are the synthetic truth when no wrong match joined them).
  size_t near = 0, total = 0;
  for (const auto& [id, point] : rec.points) {
    const auto& e = point.track.front();
    const auto it = s.keypoint_point.at(e.image_id).find(e.point2d_idx);
    if (it == s.keypoint_point.at(e.image_id).end()) continue;
    ++total;
    near += (errors->alignment.apply(point.xyz) - s.points[it->second]).norm() < 0.05;
  }
  EXPECT_GT(near, 0.99 * total);
}

TEST(IncrementalMapper, LoopClosingPairsJoinTheEndsOfALongSequence) {
  // One camera, 14 stations: the first and last stations only meet through the tracks.
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 14;
  o.outlier_ratio = 0.02;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const MapperResult result = IncrementalMapper(s.input, MapperOptions{}).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  EXPECT_EQ(result.reconstruction.images.size(), 14u);
  const auto errors = poseErrorsAfterAlignment(result.reconstruction.images, s.truth);
  ASSERT_TRUE(errors);
  EXPECT_LT(errors->max_position, 0.03);
}

TEST(IncrementalMapper, ReportsNoInitialPairWithTheNumbers) {
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 3;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  MapperOptions options;
  options.init_min_inliers = 100000;  // more than any pair holds
  const MapperResult result = IncrementalMapper(s.input, options).run();
  EXPECT_EQ(result.status, MapperStatus::NO_INITIAL_PAIR);
  EXPECT_NE(result.message.find("no initial pair among"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("100000"), std::string::npos) << result.message;
  EXPECT_TRUE(result.reconstruction.images.empty());

  SfmInput none = s.input;
  none.pairs.clear();
  const MapperResult empty = IncrementalMapper(none, MapperOptions{}).run();
  EXPECT_EQ(empty.status, MapperStatus::NO_INPUT);
  EXPECT_NE(empty.message.find("0 verified pairs"), std::string::npos) << empty.message;
}

TEST(IncrementalMapper, RejectsBadOptionsAndInputAtConstruction) {
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 2;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  MapperOptions options;
  options.max_reprojection_error_px = 0;
  try {
    IncrementalMapper mapper(s.input, options);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("max_reprojection_error_px = 0"), std::string::npos);
  }
  options = MapperOptions{};
  options.ba.num_threads = 0;
  EXPECT_THROW(IncrementalMapper(s.input, options), OptionError);
  SfmInput broken = s.input;
  broken.views[0].camera_id = 42;
  EXPECT_THROW(IncrementalMapper(broken, MapperOptions{}), std::invalid_argument);
}

TEST(IncrementalMapper, SelfCalibratesTheFocalOfAnUncalibratedCameraAndResetsARunaway) {
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 12;
  o.noise_px = 0.3;
  testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const double true_focal = s.input.cameras.at(1).fx;  // 800 px
  scene::Camera& prior = s.input.cameras.at(1);
  prior.fx *= 1.15;  // an EXIF prior 15 % off
  prior.fy *= 1.15;
  s.input.uncalibrated = {1};

  MapperOptions options;
  MapperResult result = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  const scene::Camera& refined = result.reconstruction.cameras.at(1);
  EXPECT_NEAR(refined.fx / true_focal, 1.0, 0.01);
  EXPECT_DOUBLE_EQ(refined.fy / refined.fx, 1.0);  // aspect kept
  EXPECT_DOUBLE_EQ(refined.cx, prior.cx);          // principal point not refined by default
  EXPECT_TRUE(result.intrinsics_reset.empty());
  EXPECT_LT(result.reconstruction.meanReprojectionError(), 0.6);

  // Not refined when told so: the prior stays, and the error shows it.
  options.refine_focal_length = false;
  result = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  EXPECT_DOUBLE_EQ(result.reconstruction.cameras.at(1).fx, prior.fx);

  // A refinement beyond max_focal_ratio of the prior is a runaway: reset, kept, flagged.
  options.refine_focal_length = true;
  options.max_focal_ratio = 1.05;
  result = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  EXPECT_DOUBLE_EQ(result.reconstruction.cameras.at(1).fx, prior.fx);
  ASSERT_EQ(result.intrinsics_reset.count(1), 1u);
  EXPECT_NE(result.intrinsics_reset.at(1).find("ran away"), std::string::npos);

  // A calibrated camera is never refined.
  s.input.uncalibrated.clear();
  options.max_focal_ratio = 2.0;
  result = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  EXPECT_DOUBLE_EQ(result.reconstruction.cameras.at(1).fx, prior.fx);
}

TEST(IncrementalMapper, SelfCalibratesTheRadialDistortionOfAnUncalibratedLens) {
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 12;
  o.noise_px = 0.3;
  o.k1 = -0.25;  // a barrel lens like a phone's: 11 % at the corners
  o.k2 = 0.08;
  testing::SyntheticScene s = testing::makeSyntheticScene(o);
  const double true_focal = s.input.cameras.at(1).fx;
  scene::Camera& prior = s.input.cameras.at(1);
  prior.fx *= 1.1;
  prior.fy *= 1.1;
  s.input.uncalibrated = {1};

  MapperOptions options;
  MapperResult result = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(result.status, MapperStatus::SUCCESS) << result.message;
  const scene::Camera& refined = result.reconstruction.cameras.at(1);
  EXPECT_EQ(refined.model, scene::CameraModel::OPENCV);
  ASSERT_EQ(refined.distortion.size(), 4u);
  EXPECT_NEAR(refined.fx / true_focal, 1.0, 0.01);
  EXPECT_NEAR(refined.distortion[0], o.k1, 0.03);
  EXPECT_DOUBLE_EQ(refined.distortion[2], 0.0);  // tangential not refined by default
  EXPECT_TRUE(result.intrinsics_reset.empty());
  EXPECT_LT(result.reconstruction.meanReprojectionError(), 0.6);
  EXPECT_EQ(result.reconstruction.images.size(), s.input.views.size());

  // The focal alone absorbs the lens: further off, and the error shows it.
  options.refine_radial_distortion = false;
  MapperResult focal_only = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(focal_only.status, MapperStatus::SUCCESS) << focal_only.message;
  EXPECT_FALSE(focal_only.reconstruction.cameras.at(1).hasDistortion());
  EXPECT_GT(std::abs(focal_only.reconstruction.cameras.at(1).fx / true_focal - 1.0),
            std::abs(refined.fx / true_focal - 1.0));
  EXPECT_GT(focal_only.reconstruction.meanReprojectionError(),
            result.reconstruction.meanReprojectionError() + 0.2);
}

TEST(IncrementalMapper, LeavesTwoViewTracksOutsideTheInitialPairUntriangulated) {
  testing::SyntheticOptions o;
  o.cameras = 1;
  o.stations = 10;
  const testing::SyntheticScene s = testing::makeSyntheticScene(o);
  auto twoViewPoints = [](const MapperResult& r) {
    size_t n = 0;
    for (const auto& [id, point] : r.reconstruction.points) {
      const bool initial =
          point.track.size() == 2 && ((point.track[0].image_id == r.initial_pair.first &&
                                       point.track[1].image_id == r.initial_pair.second) ||
                                      (point.track[0].image_id == r.initial_pair.second &&
                                       point.track[1].image_id == r.initial_pair.first));
      n += point.track.size() == 2 && !initial;
    }
    return n;
  };
  MapperOptions options;
  const MapperResult ignored = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(ignored.status, MapperStatus::SUCCESS) << ignored.message;
  options.ignore_two_view_tracks = false;
  const MapperResult kept = IncrementalMapper(s.input, options).run();
  ASSERT_EQ(kept.status, MapperStatus::SUCCESS) << kept.message;
  // Only the initial pair (or a track that lost observations as outliers) keeps two views.
  EXPECT_GT(twoViewPoints(kept), 50u);
  EXPECT_LT(twoViewPoints(ignored), twoViewPoints(kept) / 5);
  EXPECT_GT(ignored.reconstruction.meanTrackLength(), kept.reconstruction.meanTrackLength());
  EXPECT_EQ(ignored.reconstruction.images.size(), kept.reconstruction.images.size());
}

}  // namespace
}  // namespace auv::recon::sfm
