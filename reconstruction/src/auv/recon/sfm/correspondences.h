#pragma once
// What incremental SfM starts from (paper section 3.4.2): the undistorted views with their
// keypoints, the verified pairwise matches, and the tracks built from them.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/scene/camera.h"
#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::sfm {

/// One image to reconstruct: undistorted keypoints of a PINHOLE camera.
struct View {
  uint32_t id = 0;
  uint32_t camera_id = 0;
  std::string name;  ///< relative to corrected/, e.g. "left/left_0001_000123.png"
  std::vector<Eigen::Vector2d> keypoints;  ///< px, OpenCV convention (pixel centres at integers)
};

/// Geometrically verified matches of one image pair (keypoint index in a, keypoint index in b).
struct ViewPair {
  uint32_t image_a = 0, image_b = 0;
  std::vector<std::pair<uint32_t, uint32_t>> matches;
  /// Matches a homography explains, when the verification measured it (-1: unknown, SfM
  /// fits one itself when it considers the pair as initial pair).
  int64_t homography_inliers = -1;
  /// The verification's essential matrix (x_b^T E x_a = 0, normalised coordinates), when it
  /// had one: SfM decomposes it instead of fitting one again for a candidate initial pair.
  std::optional<Eigen::Matrix3d> essential;
};

struct SfmInput {
  std::map<uint32_t, scene::Camera> cameras;  ///< intrinsics, one per physical camera
  /// Cameras whose intrinsics are a prior, not a calibration: self-calibrated in global bundle
  /// adjustment (MapperOptions::refine_focal_length); the others stay fixed.
  std::set<uint32_t> uncalibrated;
  std::vector<View> views;
  std::vector<ViewPair> pairs;

  /// Throws std::invalid_argument naming the first broken reference (unknown camera or image,
  /// keypoint index out of range, duplicate image id, pair of an image with itself, camera
  /// with distortion or without a focal length).
  void check() const;
};

struct TrackStats {
  size_t tracks = 0;               ///< with >= 2 images
  size_t observations = 0;         ///< keypoints in tracks
  size_t conflicting_matches = 0;  ///< left out: they would put two keypoints of one image
                                   ///< in one track
};

/// Tracks: the connected components of the match graph over (image, keypoint) nodes, found
/// with union-find. A track holding two keypoints of one image is inconsistent (a wrong match
/// somewhere). Dropping whole components would let a few wrong matches chain thousands of
/// tracks into one and lose them all; instead the union is constrained: pairs are joined
/// strongest first (most matches), and a match whose two tracks already share an image is
/// left out and counted. No track ever holds two keypoints of one image.
class Tracks {
 public:
  static constexpr int64_t kNoTrack = -1;

  /// `input` must have passed check().
  static Tracks build(const SfmInput& input);

  size_t size() const { return tracks_.size(); }
  const std::vector<scene::TrackElement>& track(size_t id) const { return tracks_[id]; }
  /// Track of a keypoint, kNoTrack when it belongs to none.
  int64_t trackOf(uint32_t image_id, uint32_t keypoint) const;
  /// Per keypoint of an image, its track or kNoTrack.
  const std::vector<int64_t>& tracksOfImage(uint32_t image_id) const;
  const TrackStats& stats() const { return stats_; }

 private:
  std::vector<std::vector<scene::TrackElement>> tracks_;
  std::map<uint32_t, std::vector<int64_t>> keypoint_tracks_;
  TrackStats stats_;
};

}  // namespace auv::recon::sfm
