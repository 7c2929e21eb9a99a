#pragma once
// Steps 3 and 4 of dense matching (docs/paper.md §3.5; the paper: "a 3D point cloud is later
// obtained by projecting the points to space according to the camera's pose and associated depth
// value"):
// geometric consistency across views and fusion into one coloured, oriented point cloud that
// records which images saw each point.
//
// A master pixel's depth is consistent with a neighbour when, projected into the neighbour,
// the neighbour's depth there agrees within a relative tolerance and the neighbour's point
// projects back within a pixel tolerance of the master pixel (forward-backward check, as in
// COLMAP's fusion). Depths with fewer than min_consistent agreeing neighbours are dropped;
// the others become one point: the mean of the master's and the agreeing neighbours' points,
// normals and colours. Neighbour pixels used by a point are not used again (no duplicates);
// new points start on a grid of pixel_step px of the master (the cloud's density).

#include <cstdint>
#include <filesystem>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/dense/view.h"

namespace auv::recon::dense {

struct FusionOptions {
  int min_consistent = 2;         ///< neighbours whose depth maps must agree
  double depth_tolerance = 0.02;  ///< relative depth difference allowed
  double reprojection_px = 2.0;   ///< forward-backward reprojection error allowed, px
  int normal_step = 2;            ///< px between the depths normals are computed from
  int pixel_step = 2;  ///< new points start only at master pixels on this grid (density 1/step^2)

  void check() const;
};

/// What fusion needs of an image: its view at the depth map's size (colour loaded), its depth
/// map (CV_32F, 0 = none) and world normals (CV_32FC3, normalsFromDepth).
struct FusionView {
  View view;
  cv::Mat depth;
  cv::Mat normals;
};

/// Per master pixel, the number of neighbours whose depth maps agree with its depth (CV_8U;
/// 0 where the master has no depth).
cv::Mat consistentNeighbours(const FusionView& master,
                             const std::vector<const FusionView*>& neighbours,
                             const FusionOptions& options);

/// The master's depth map with the depths of fewer than min_consistent agreeing neighbours
/// set to 0.
cv::Mat filterDepthMap(const FusionView& master, const std::vector<const FusionView*>& neighbours,
                       const FusionOptions& options);

/// Image ids per point, packed: point i has ids[offsets[i] .. offsets[i + 1]).
struct PointViews {
  std::vector<uint64_t> offsets{0};
  std::vector<uint32_t> ids;

  size_t size() const { return offsets.size() - 1; }
  std::vector<uint32_t> of(size_t point) const {
    return {ids.begin() + offsets[point], ids.begin() + offsets[point + 1]};
  }
  void add(const std::vector<uint32_t>& point_ids) {
    ids.insert(ids.end(), point_ids.begin(), point_ids.end());
    offsets.push_back(ids.size());
  }
};

/// The fused cloud (single precision: hundreds of images give millions of points).
struct FusedCloud {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;              ///< unit, towards the cameras
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;  ///< RGB
  PointViews images;                                 ///< contributing image ids, sorted

  size_t size() const { return positions.size(); }
};

struct FusionStats {
  size_t depths = 0;        ///< master pixels with a depth, not used by an earlier point
  size_t inconsistent = 0;  ///< of these, dropped by the consistency check
  size_t points = 0;        ///< points added
};

class Fuser {
 public:
  explicit Fuser(FusionOptions options);

  /// Adds the master's consistent, unused pixels as points.
  FusionStats add(const FusionView& master, const std::vector<const FusionView*>& neighbours);
  const FusedCloud& cloud() const { return cloud_; }
  FusedCloud release() { return std::move(cloud_); }

 private:
  std::vector<bool>& used(const FusionView& view);

  FusionOptions options_;
  FusedCloud cloud_;
  std::unordered_map<uint32_t, std::vector<bool>> used_;  ///< per image id, per pixel
};

/// The contributing images of each point: `fused_views.bin` beside fused.ply, little-endian:
/// uint64 number of points, then per point (in PLY vertex order) uint32 n and n uint32 image
/// ids of the sparse model (images.txt; their camera ids give the camera combination).
void writeFusedViews(const std::filesystem::path& file, const PointViews& images);
/// Throws std::runtime_error naming the file when it is missing, truncated or malformed.
PointViews readPointViews(const std::filesystem::path& file);
/// The same, one list per point (convenient for small clouds).
std::vector<std::vector<uint32_t>> readFusedViews(const std::filesystem::path& file);

}  // namespace auv::recon::dense
