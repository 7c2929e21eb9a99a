#include "auv/recon/sfm/incremental_mapper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "auv/recon/common/progress.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/sfm/triangulation.h"

namespace auv::recon::sfm {

void MapperOptions::check() const {
  AUV_RECON_CHECK_OPTION(init_min_inliers >= 8, init_min_inliers, "must be >= 8");
  AUV_RECON_CHECK_OPTION(init_min_tri_angle_deg > 0 && init_min_tri_angle_deg < 90,
                         init_min_tri_angle_deg, "must be in (0, 90) deg");
  AUV_RECON_CHECK_OPTION(init_max_homography_ratio > 0 && init_max_homography_ratio <= 1,
                         init_max_homography_ratio, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(init_max_pairs > 0, init_max_pairs, "must be > 0");
  AUV_RECON_CHECK_OPTION(init_relaxations >= 0 && init_relaxations <= 10, init_relaxations,
                         "must be in [0, 10]");
  AUV_RECON_CHECK_OPTION(abs_pose_min_inliers >= 4, abs_pose_min_inliers, "must be >= 4");
  AUV_RECON_CHECK_OPTION(abs_pose_min_inlier_ratio >= 0 && abs_pose_min_inlier_ratio <= 1,
                         abs_pose_min_inlier_ratio, "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(max_registration_trials > 0, max_registration_trials, "must be > 0");
  AUV_RECON_CHECK_OPTION(min_tri_angle_deg >= 0 && min_tri_angle_deg < 90, min_tri_angle_deg,
                         "must be in [0, 90) deg");
  AUV_RECON_CHECK_OPTION(max_reprojection_error_px > 0, max_reprojection_error_px,
                         "must be > 0 px");
  AUV_RECON_CHECK_OPTION(local_ba_images >= 1, local_ba_images, "must be >= 1");
  AUV_RECON_CHECK_OPTION(global_ba_growth > 0, global_ba_growth, "must be > 0");
  AUV_RECON_CHECK_OPTION(local_ba_max_iterations > 0, local_ba_max_iterations, "must be > 0");
  AUV_RECON_CHECK_OPTION(global_ba_max_iterations > 0, global_ba_max_iterations, "must be > 0");
  AUV_RECON_CHECK_OPTION(max_focal_ratio > 1, max_focal_ratio, "must be > 1");
  ba.check();
  robust.check();
}

std::string mapperStatusName(MapperStatus status) {
  switch (status) {
    case MapperStatus::SUCCESS:
      return "SUCCESS";
    case MapperStatus::NO_INITIAL_PAIR:
      return "NO_INITIAL_PAIR";
    case MapperStatus::NO_INPUT:
      return "NO_INPUT";
  }
  return "?";
}

namespace {
constexpr double kDeg = M_PI / 180.0;

using Clock = std::chrono::steady_clock;
/// Adds the time of a scope to a sub-stage's counter.
class ScopedTimer {
 public:
  explicit ScopedTimer(double& seconds) : seconds_(seconds), start_(Clock::now()) {}
  ~ScopedTimer() { seconds_ += std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  double& seconds_;
  Clock::time_point start_;
};

Matrix34d poseMatrix(const scene::Image& image) {
  Matrix34d p;
  p.leftCols<3>() = image.rotation();
  p.col(3) = image.t_cw;
  return p;
}
}  // namespace

IncrementalMapper::IncrementalMapper(SfmInput input, MapperOptions options)
    : input_(std::move(input)), options_(std::move(options)) {
  options_.check();
  input_.check();
  for (const View& view : input_.views) views_[view.id] = &view;
  rec_.cameras = input_.cameras;
}

void IncrementalMapper::logLine(const std::string& line) const {
  if (log_) log_(line);
}

double IncrementalMapper::reprojectionError(const scene::Image& image, uint32_t keypoint,
                                            const Eigen::Vector3d& xyz) const {
  const Eigen::Vector3d p = image.toCamera(xyz);
  if (p.z() <= 0) return std::numeric_limits<double>::infinity();
  return (rec_.cameraOf(image).project(p) - image.points2d[keypoint]).norm();
}

double IncrementalMapper::maxTriangulationAngle(const scene::Point3D& point) const {
  double best = 0;
  const size_t n = std::min<size_t>(point.track.size(), 12);  // enough to decide
  std::vector<Eigen::Vector3d> centers;
  for (size_t i = 0; i < n; ++i)
    centers.push_back(rec_.images.at(point.track[i].image_id).center());
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      best = std::max(best, triangulationAngle(centers[i], centers[j], point.xyz));
    }
  }
  return best;
}

void IncrementalMapper::addImage(uint32_t id, const Eigen::Quaterniond& q_cw,
                                 const Eigen::Vector3d& t_cw) {
  const View& view = *views_.at(id);
  scene::Image image;
  image.id = id;
  image.camera_id = view.camera_id;
  image.name = view.name;
  image.q_cw = q_cw.normalized();
  image.t_cw = t_cw;
  image.points2d = view.keypoints;
  image.point3d_ids.assign(view.keypoints.size(), scene::kNoPoint3D);
  rec_.images[id] = std::move(image);
}

void IncrementalMapper::addObservation(uint64_t point, const scene::TrackElement& element) {
  rec_.points.at(point).track.push_back(element);
  rec_.images.at(element.image_id).point3d_ids[element.point2d_idx] = static_cast<int64_t>(point);
}

void IncrementalMapper::deletePoint(uint64_t point) {
  auto it = rec_.points.find(point);
  if (it == rec_.points.end()) return;
  for (const auto& e : it->second.track) {
    rec_.images.at(e.image_id).point3d_ids[e.point2d_idx] = scene::kNoPoint3D;
  }
  rec_.points.erase(it);
}

bool IncrementalMapper::triangulateTrack(uint64_t track, bool initial) {
  if (rec_.points.count(track)) return false;
  if (options_.ignore_two_view_tracks && !initial && tracks_.track(track).size() < 3) return false;
  std::vector<scene::TrackElement> elements;
  std::vector<PosedObservation> observations;
  for (const auto& e : tracks_.track(track)) {
    auto it = rec_.images.find(e.image_id);
    if (it == rec_.images.end()) continue;
    elements.push_back(e);
    observations.push_back(
        {poseMatrix(it->second),
         rec_.cameraOf(it->second).pixelToNormalized(it->second.points2d[e.point2d_idx])});
  }
  if (elements.size() < 2) return false;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::optional<Eigen::Vector3d> dlt = triangulateDlt(observations);
    if (!dlt) return false;
    const Eigen::Vector3d xyz = refineTriangulation(observations, *dlt);
    // Keep the observations it explains; one retry without the others.
    std::vector<scene::TrackElement> kept;
    std::vector<PosedObservation> kept_observations;
    for (size_t i = 0; i < elements.size(); ++i) {
      const scene::Image& image = rec_.images.at(elements[i].image_id);
      if (reprojectionError(image, elements[i].point2d_idx, xyz) <=
          options_.max_reprojection_error_px) {
        kept.push_back(elements[i]);
        kept_observations.push_back(observations[i]);
      }
    }
    if (kept.size() < 2) return false;
    if (kept.size() < elements.size() && attempt == 0) {
      elements = std::move(kept);
      observations = std::move(kept_observations);
      continue;
    }
    scene::Point3D point;
    point.id = track;
    point.xyz = xyz;
    point.track = kept;
    if (maxTriangulationAngle(point) < options_.min_tri_angle_deg * kDeg) return false;
    point.track.clear();
    rec_.points.emplace(track, std::move(point));
    for (const auto& e : kept) addObservation(track, e);
    return true;
  }
  return false;
}

size_t IncrementalMapper::completePoint(uint64_t track) {
  auto it = rec_.points.find(track);
  if (it == rec_.points.end()) return 0;
  size_t added = 0;
  for (const auto& e : tracks_.track(track)) {
    auto image = rec_.images.find(e.image_id);
    if (image == rec_.images.end()) continue;
    if (image->second.point3d_ids[e.point2d_idx] == static_cast<int64_t>(track)) continue;
    if (reprojectionError(image->second, e.point2d_idx, it->second.xyz) <=
        options_.max_reprojection_error_px) {
      addObservation(track, e);
      ++added;
    }
  }
  return added;
}

size_t IncrementalMapper::filterPoints(const std::set<uint64_t>& points) {
  size_t removed = 0;
  for (uint64_t id : points) {
    auto it = rec_.points.find(id);
    if (it == rec_.points.end()) continue;
    scene::Point3D& point = it->second;
    std::vector<scene::TrackElement> kept;
    for (const auto& e : point.track) {
      scene::Image& image = rec_.images.at(e.image_id);
      if (reprojectionError(image, e.point2d_idx, point.xyz) <=
          options_.max_reprojection_error_px) {
        kept.push_back(e);
      } else {
        image.point3d_ids[e.point2d_idx] = scene::kNoPoint3D;
        ++removed;
      }
    }
    point.track = std::move(kept);
    if (point.track.size() < 2 ||
        maxTriangulationAngle(point) < options_.min_tri_angle_deg * kDeg) {
      removed += point.track.size();
      deletePoint(id);
    }
  }
  return removed;
}

void IncrementalMapper::evaluatePair(PairCandidate& pair) {
  pair.evaluated = true;
  const View& a = *views_.at(pair.a);
  const View& b = *views_.at(pair.b);
  // Correspondences through the tracks (consistent ones only).
  std::vector<Eigen::Vector2d> pa, pb;
  std::map<int64_t, uint32_t> in_b;
  const std::vector<int64_t>& tb = tracks_.tracksOfImage(b.id);
  for (uint32_t k = 0; k < tb.size(); ++k) {
    if (tb[k] != Tracks::kNoTrack) in_b[tb[k]] = k;
  }
  const std::vector<int64_t>& ta = tracks_.tracksOfImage(a.id);
  for (uint32_t k = 0; k < ta.size(); ++k) {
    if (ta[k] == Tracks::kNoTrack) continue;
    auto it = in_b.find(ta[k]);
    if (it == in_b.end()) continue;
    pa.push_back(a.keypoints[k]);
    pb.push_back(b.keypoints[it->second]);
  }
  pair.correspondences = pa.size();
  if (pa.size() < options_.init_min_inliers) return;
  const scene::Camera& ca = input_.cameras.at(a.camera_id);
  const scene::Camera& cb = input_.cameras.at(b.camera_id);
  pair.pose = pair.essential
                  ? relativePoseFromEssential(*pair.essential, ca, cb, pa, pb, options_.robust)
                  : estimateRelativePose(ca, cb, pa, pb, options_.robust);
  if (!pair.pose.found || pair.pose.inliers.size() < options_.init_min_inliers) return;
  // Planar scene or no baseline when a homography explains about as much (the verification's
  // count over all its matches when it has one).
  const int64_t h =
      pair.homography_inliers >= 0
          ? pair.homography_inliers
          : static_cast<int64_t>(countHomographyInliers(ca, cb, pa, pb, options_.robust));
  const double e = pair.homography_inliers >= 0 ? pair.matches : pair.pose.inliers.size();
  pair.homography_ratio = h / std::max(e, 1.0);
  // Median triangulation angle of the inliers in front of both cameras.
  Matrix34d pose_a = Matrix34d::Zero(), pose_b;
  pose_a.leftCols<3>().setIdentity();
  pose_b.leftCols<3>() = pair.pose.rotation;
  pose_b.col(3) = pair.pose.translation;
  const Eigen::Vector3d center_b = -pair.pose.rotation.transpose() * pair.pose.translation;
  std::vector<double> angles;
  for (uint32_t i : pair.pose.inliers) {
    const std::vector<PosedObservation> obs = {{pose_a, ca.pixelToNormalized(pa[i])},
                                               {pose_b, cb.pixelToNormalized(pb[i])}};
    const auto x = triangulateDlt(obs);
    if (!x || depthIn(pose_a, *x) <= 0 || depthIn(pose_b, *x) <= 0) continue;
    angles.push_back(triangulationAngle(Eigen::Vector3d::Zero(), center_b, *x));
  }
  if (angles.size() < options_.init_min_inliers) return;
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  pair.median_angle = angles[angles.size() / 2];
}

void IncrementalMapper::buildInitialPair(const PairCandidate& pair) {
  addImage(pair.a, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  addImage(pair.b, Eigen::Quaterniond(pair.pose.rotation), pair.pose.translation);
  for (int64_t t : tracks_.tracksOfImage(pair.a)) {
    if (t != Tracks::kNoTrack) triangulateTrack(static_cast<uint64_t>(t), true);
  }
  std::ostringstream line;
  line << "sfm: initial pair " << views_.at(pair.a)->name << " + " << views_.at(pair.b)->name
       << ": " << pair.pose.inliers.size() << " inliers of " << pair.correspondences
       << ", homography/essential " << pair.homography_ratio << ", median triangulation angle "
       << pair.median_angle / kDeg << " deg, " << rec_.points.size() << " points";
  logLine(line.str());
}

bool IncrementalMapper::findInitialPair(MapperResult& result) {
  pair_candidates_.clear();
  for (const ViewPair& pair : input_.pairs) {
    if (pair.matches.size() < options_.init_min_inliers) continue;
    PairCandidate candidate;
    candidate.a = pair.image_a;
    candidate.b = pair.image_b;
    candidate.matches = pair.matches.size();
    candidate.homography_inliers = pair.homography_inliers;
    candidate.essential = pair.essential;
    pair_candidates_.push_back(candidate);
  }
  std::stable_sort(
      pair_candidates_.begin(), pair_candidates_.end(),
      [](const PairCandidate& x, const PairCandidate& y) { return x.matches > y.matches; });
  if (pair_candidates_.size() > options_.init_max_pairs) {
    pair_candidates_.resize(options_.init_max_pairs);
  }
  std::set<size_t> rejected;  // built, then too few points after bundle adjustment
  double angle = options_.init_min_tri_angle_deg * kDeg;
  for (int round = 0; round <= options_.init_relaxations + 1; ++round) {
    const bool planar_ok = round == options_.init_relaxations + 1;
    for (size_t i = 0; i < pair_candidates_.size(); ++i) {
      PairCandidate& pair = pair_candidates_[i];
      if (rejected.count(i)) continue;
      if (!pair.evaluated) evaluatePair(pair);
      if (pair.pose.inliers.size() < options_.init_min_inliers || pair.median_angle < angle ||
          (!planar_ok && pair.homography_ratio > options_.init_max_homography_ratio)) {
        continue;
      }
      buildInitialPair(pair);
      // Two-view bundle adjustment; the pair must still hold enough points.
      initial_pair_ = {pair.a, pair.b};
      globalBundleAdjustment(result, options_.global_ba_max_iterations, false);
      std::set<uint64_t> all;
      for (const auto& [id, p] : rec_.points) all.insert(id);
      filterPoints(all);
      if (rec_.points.size() >= options_.init_min_inliers / 2) return true;
      logLine("sfm: initial pair rejected after bundle adjustment: " +
              std::to_string(rec_.points.size()) + " points left");
      rejected.insert(i);
      rec_.images.clear();
      rec_.points.clear();
    }
    if (round < options_.init_relaxations) angle /= 2;
  }
  return false;
}

std::vector<uint32_t> IncrementalMapper::nextCandidates() const {
  std::vector<std::pair<size_t, uint32_t>> scored;
  for (const View& view : input_.views) {
    if (rec_.images.count(view.id)) continue;
    auto f = failed_trials_.find(view.id);
    if (f != failed_trials_.end() && f->second >= options_.max_registration_trials) continue;
    size_t visible = 0;
    for (int64_t t : tracks_.tracksOfImage(view.id)) {
      visible += t != Tracks::kNoTrack && rec_.points.count(static_cast<uint64_t>(t));
    }
    if (visible >= options_.abs_pose_min_inliers) scored.push_back({visible, view.id});
  }
  std::sort(scored.begin(), scored.end(), [](const auto& x, const auto& y) {
    return x.first != y.first ? x.first > y.first : x.second < y.second;
  });
  std::vector<uint32_t> out;
  for (const auto& s : scored) out.push_back(s.second);
  return out;
}

bool IncrementalMapper::registerImage(uint32_t id) {
  const View& view = *views_.at(id);
  // The model's intrinsics: self-calibration may have refined the input's prior.
  const scene::Camera& camera = rec_.cameras.at(view.camera_id);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<uint32_t> keypoints;
  const std::vector<int64_t>& tracks = tracks_.tracksOfImage(id);
  for (uint32_t k = 0; k < tracks.size(); ++k) {
    if (tracks[k] == Tracks::kNoTrack) continue;
    auto it = rec_.points.find(static_cast<uint64_t>(tracks[k]));
    if (it == rec_.points.end()) continue;
    points.push_back(it->second.xyz);
    pixels.push_back(view.keypoints[k]);
    keypoints.push_back(k);
  }
  if (points.size() < options_.abs_pose_min_inliers) return false;
  AbsolutePose pose = estimateAbsolutePose(camera, points, pixels, options_.robust);
  if (!pose.found || pose.inliers.size() < options_.abs_pose_min_inliers ||
      pose.inliers.size() < options_.abs_pose_min_inlier_ratio * points.size()) {
    std::ostringstream why;
    why << pose.inliers.size() << " inliers of " << points.size()
        << " 2D-3D correspondences (needs >= " << options_.abs_pose_min_inliers
        << " and >= " << 100.0 * options_.abs_pose_min_inlier_ratio << " %)";
    last_failure_[id] = why.str();
    logLine("sfm: " + view.name + " not registered: " + why.str());
    return false;
  }
  refineAbsolutePose(camera, points, pixels, pose.inliers, options_.ba, pose.q_cw, pose.t_cw);
  addImage(id, pose.q_cw, pose.t_cw);
  const scene::Image& image = rec_.images.at(id);
  for (size_t i = 0; i < points.size(); ++i) {
    if (reprojectionError(image, keypoints[i], points[i]) <= options_.max_reprojection_error_px) {
      addObservation(static_cast<uint64_t>(tracks[keypoints[i]]), {id, keypoints[i]});
    }
  }
  return true;
}

size_t IncrementalMapper::triangulateImage(uint32_t id) {
  size_t created = 0;
  for (int64_t t : tracks_.tracksOfImage(id)) {
    if (t == Tracks::kNoTrack) continue;
    if (rec_.points.count(static_cast<uint64_t>(t))) {
      completePoint(static_cast<uint64_t>(t));
    } else {
      created += triangulateTrack(static_cast<uint64_t>(t));
    }
  }
  return created;
}

void IncrementalMapper::localBundleAdjustment(uint32_t id, MapperResult& result) {
  // Neighbours: the registered views sharing the most points with the new one.
  std::map<uint32_t, size_t> shared;
  for (int64_t p : rec_.images.at(id).point3d_ids) {
    if (p == scene::kNoPoint3D) continue;
    for (const auto& e : rec_.points.at(static_cast<uint64_t>(p)).track) {
      if (e.image_id != id) ++shared[e.image_id];
    }
  }
  std::vector<std::pair<size_t, uint32_t>> order;
  for (const auto& [image, n] : shared) order.push_back({n, image});
  std::sort(order.rbegin(), order.rend());
  BundleAdjustmentConfig config;
  config.images.insert(id);
  for (size_t i = 0; i < order.size() && config.images.size() < options_.local_ba_images; ++i) {
    config.images.insert(order[i].second);
  }
  // The initial pair keeps the gauge while it is part of a small model.
  if (config.images.size() >= rec_.images.size() - 1) {
    config.constant_images.insert(initial_pair_.first);
  }
  {
    ScopedTimer timer(timings_->local_ba);
    BundleAdjustmentOptions ba = options_.ba;
    ba.max_iterations = options_.local_ba_max_iterations;
    bundleAdjust(rec_, config, ba);
    ++result.local_bas;
  }
  ScopedTimer timer(timings_->filtering);
  std::set<uint64_t> points;
  for (uint32_t image : config.images) {
    for (int64_t p : rec_.images.at(image).point3d_ids) {
      if (p != scene::kNoPoint3D) points.insert(static_cast<uint64_t>(p));
    }
  }
  for (uint64_t p : points) completePoint(p);
  filterPoints(points);
}

void IncrementalMapper::globalBundleAdjustment(MapperResult& result, int max_iterations,
                                               bool timed) {
  double untimed = 0;
  ScopedTimer timer(timed ? timings_->global_ba : untimed);
  BundleAdjustmentConfig config;
  for (const auto& [id, image] : rec_.images) config.images.insert(id);
  config.constant_images.insert(initial_pair_.first != initial_pair_.second
                                    ? initial_pair_.first
                                    : rec_.images.begin()->first);
  if (options_.refine_focal_length) {
    for (uint32_t camera : input_.uncalibrated) {
      if (!result.intrinsics_reset.count(camera)) config.refine_focal.insert(camera);
    }
    config.refine_principal_point = options_.refine_principal_point;
    config.refine_radial_distortion = options_.refine_radial_distortion;
    config.refine_tangential_distortion = options_.refine_tangential_distortion;
  }
  BundleAdjustmentOptions ba = options_.ba;
  ba.max_iterations = max_iterations;
  bundleAdjust(rec_, config, ba);
  ++result.global_bas;
  for (uint32_t id : config.refine_focal) resetRunawayIntrinsics(id, result);
}

std::map<uint32_t, size_t> IncrementalMapper::separateGroups() const {
  std::map<uint32_t, std::vector<uint32_t>> neighbours;
  for (const ViewPair& pair : input_.pairs) {
    neighbours[pair.image_a].push_back(pair.image_b);
    neighbours[pair.image_b].push_back(pair.image_a);
  }
  // Each group of images its verified pairs join, transitively, once: a group without an image
  // in the model is one no verified pair joins to it (another camera in murk, a second visit).
  std::map<uint32_t, size_t> separate;
  std::set<uint32_t> seen;
  for (const auto& [start, unused] : neighbours) {
    if (!seen.insert(start).second) continue;
    std::vector<uint32_t> group{start};
    for (size_t next = 0; next < group.size(); ++next) {
      for (uint32_t other : neighbours[group[next]]) {
        if (seen.insert(other).second) group.push_back(other);
      }
    }
    if (std::none_of(group.begin(), group.end(),
                     [&](uint32_t image) { return rec_.images.count(image) > 0; })) {
      for (uint32_t image : group) separate[image] = group.size();
    }
  }
  return separate;
}

std::string IncrementalMapper::whyUnregistered(uint32_t id,
                                               const std::map<uint32_t, size_t>& separate) const {
  const auto failed = last_failure_.find(id);
  if (failed != last_failure_.end()) return failed->second;
  const bool paired = std::any_of(input_.pairs.begin(), input_.pairs.end(), [&](const ViewPair& p) {
    return p.image_a == id || p.image_b == id;
  });
  if (!paired) return "no verified pair: it matched no other image";
  const auto group = separate.find(id);
  if (group != separate.end()) {
    return "not connected to the model: its verified pairs join it only to " +
           std::to_string(group->second - 1) +
           " other unregistered image(s), a separate group (the model holds one group)";
  }
  size_t visible = 0;
  for (int64_t t : tracks_.tracksOfImage(id)) {
    visible += t != Tracks::kNoTrack && rec_.points.count(static_cast<uint64_t>(t));
  }
  std::ostringstream why;
  why << "only " << visible << " of its keypoints see points of the model (a resection needs >= "
      << options_.abs_pose_min_inliers << ")";
  return why.str();
}

void IncrementalMapper::resetRunawayIntrinsics(uint32_t id, MapperResult& result) {
  scene::Camera& camera = rec_.cameras.at(id);
  const scene::Camera& prior = input_.cameras.at(id);
  const std::string runaway = runawayIntrinsics(camera, prior, options_.max_focal_ratio);
  if (runaway.empty()) return;
  camera = prior;
  result.intrinsics_reset[id] = runaway + ": reset to the prior and kept";
}

size_t IncrementalMapper::retriangulate() {
  size_t created = 0;
  std::set<int64_t> seen;
  for (const auto& [id, image] : rec_.images) {
    for (int64_t t : tracks_.tracksOfImage(id)) {
      if (t == Tracks::kNoTrack || !seen.insert(t).second) continue;
      if (rec_.points.count(static_cast<uint64_t>(t))) {
        completePoint(static_cast<uint64_t>(t));
      } else {
        created += triangulateTrack(static_cast<uint64_t>(t));
      }
    }
  }
  return created;
}

MapperResult IncrementalMapper::run(Progress* progress,
                                    const std::function<void(const std::string&)>& log) {
  const auto start = Clock::now();
  MapperResult result;
  timings_ = &result.timings;
  log_ = log;
  result.images_total = input_.views.size();
  rec_.images.clear();
  rec_.points.clear();
  failed_trials_.clear();
  last_failure_.clear();
  if (input_.views.size() < 2 || input_.pairs.empty()) {
    result.status = MapperStatus::NO_INPUT;
    result.message = std::to_string(input_.views.size()) + " images and " +
                     std::to_string(input_.pairs.size()) +
                     " verified pairs: at least 2 images and 1 pair are needed";
    return result;
  }
  {
    ScopedTimer timer(result.timings.tracks);
    tracks_ = Tracks::build(input_);
    result.tracks = tracks_.stats();
  }
  {
    ScopedTimer timer(result.timings.initial_pair);
    if (!findInitialPair(result)) {
      result.status = MapperStatus::NO_INITIAL_PAIR;
      size_t best = 0, most_inliers = 0;
      double widest = 0;
      for (const auto& p : input_.pairs) best = std::max(best, p.matches.size());
      for (const auto& p : pair_candidates_) {
        most_inliers = std::max(most_inliers, p.pose.inliers.size());
        widest = std::max(widest, p.median_angle);
      }
      std::ostringstream message;
      message << "no initial pair among " << input_.pairs.size() << " verified pairs ("
              << pair_candidates_.size() << " tried; most matches " << best
              << ", most essential inliers " << most_inliers
              << ", widest median triangulation angle " << widest / kDeg
              << " deg; needs >= " << options_.init_min_inliers << " inliers and >= "
              << options_.init_min_tri_angle_deg / (1 << options_.init_relaxations) << " deg)";
      result.message = message.str();
      result.timings.total = std::chrono::duration<double>(Clock::now() - start).count();
      return result;
    }
  }
  result.initial_pair = initial_pair_;
  if (progress) progress->advance(2);

  size_t images_at_last_global = rec_.images.size();
  bool global_since_last_registration = true;
  while (rec_.images.size() < input_.views.size()) {
    uint32_t registered = 0;
    bool any = false;
    {
      ScopedTimer timer(result.timings.registration);
      for (uint32_t candidate : nextCandidates()) {
        if (registerImage(candidate)) {
          registered = candidate;
          any = true;
          break;
        }
        ++failed_trials_[candidate];
      }
    }
    if (!any) {
      if (global_since_last_registration) break;
      // Points moved and grew since: one more chance for every view left.
      globalBundleAdjustment(result, options_.global_ba_max_iterations);
      ScopedTimer timer(result.timings.filtering);
      retriangulate();
      std::set<uint64_t> all;
      for (const auto& [id, p] : rec_.points) all.insert(id);
      filterPoints(all);
      failed_trials_.clear();
      global_since_last_registration = true;
      images_at_last_global = rec_.images.size();
      continue;
    }
    global_since_last_registration = false;
    if (progress) progress->advance();
    {
      ScopedTimer timer(result.timings.triangulation);
      triangulateImage(registered);
    }
    localBundleAdjustment(registered, result);
    if (rec_.images.size() >= (1 + options_.global_ba_growth) * images_at_last_global) {
      globalBundleAdjustment(result, options_.global_ba_max_iterations);
      ScopedTimer timer(result.timings.filtering);
      retriangulate();
      std::set<uint64_t> all;
      for (const auto& [id, p] : rec_.points) all.insert(id);
      filterPoints(all);
      images_at_last_global = rec_.images.size();
      global_since_last_registration = true;
    }
  }
  // Final refinement: global BA, re-triangulation, filtering, and a last global BA.
  for (int round = 0; round < 2; ++round) {
    globalBundleAdjustment(result, options_.global_ba_max_iterations);
    ScopedTimer timer(result.timings.filtering);
    retriangulate();
    std::set<uint64_t> all;
    for (const auto& [id, p] : rec_.points) all.insert(id);
    filterPoints(all);
  }
  rec_.updatePointErrors();
  const std::map<uint32_t, size_t> separate = separateGroups();
  for (const View& view : input_.views) {
    if (rec_.images.count(view.id)) continue;
    result.unregistered.push_back(view.id);
    result.unregistered_reasons[view.id] = whyUnregistered(view.id, separate);
  }
  result.status = MapperStatus::SUCCESS;
  result.reconstruction = rec_;
  result.timings.total = std::chrono::duration<double>(Clock::now() - start).count();
  timings_ = nullptr;
  return result;
}

}  // namespace auv::recon::sfm
