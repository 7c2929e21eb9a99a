#pragma once
// The part of the ground-truth surface a reconstruction can be asked to recover: the
// "well-imaged region" (issue 7: F-score goal in the well-imaged region).
//
// Definition: a point of the true surface is well imaged when at least `min_views` of the
// survey's keyframes (their true poses and true lenses) see it: it projects inside the image,
// lies in front of the camera no farther than `max_range_m` (default: the water's visibility,
// beyond which the image holds only water), is not hidden by other parts of the world (an
// occlusion ray to it reaches it), and is not seen more obliquely than `max_incidence_deg`
// from its normal. The true surface is represented by samples spread uniformly over the world
// mesh near the cameras (`sample_spacing_m` apart on average).
//
// Occlusion rays use Embree 3 directly (Open3D 0.16's ray casting returns no hits on Debian:
// its rays leave Embree's mask at 0; docs/library-notes.md).

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/scene/camera.h"

namespace open3d::geometry {
class TriangleMesh;
}

namespace auv::recon::evaluate {

/// Points spread over a surface, with the normal of the triangle each lies on.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
  size_t size() const { return points.size(); }
};

/// Samples `mesh` uniformly by area, on average one point per spacing^2 (each triangle gets
/// floor(area / spacing^2) points plus one with the remaining probability), at random positions
/// from `seed`: the same mesh and seed give the same points. Only the triangles listed in
/// `triangles` when it is not null.
SurfaceSamples sampleSurface(const open3d::geometry::TriangleMesh& mesh, double spacing_m,
                             uint64_t seed, const std::vector<size_t>* triangles = nullptr);

/// Triangles with a point within `distance_m` of one of `centers` (their circumscribing
/// sphere reaches it).
std::vector<size_t> trianglesNear(const open3d::geometry::TriangleMesh& mesh,
                                  const std::vector<Eigen::Vector3d>& centers, double distance_m);

/// A camera pose with its lens: what sees the true surface.
struct View {
  scene::Camera camera;                                       ///< true intrinsics + distortion
  Eigen::Matrix3d rotation_cw = Eigen::Matrix3d::Identity();  ///< world -> camera
  Eigen::Vector3d translation_cw = Eigen::Vector3d::Zero();
  Eigen::Vector3d center() const { return -rotation_cw.transpose() * translation_cw; }
};

/// Occlusion queries against a triangle mesh (Embree 3).
class OcclusionTester {
 public:
  explicit OcclusionTester(const open3d::geometry::TriangleMesh& mesh);
  ~OcclusionTester();
  OcclusionTester(const OcclusionTester&) = delete;
  OcclusionTester& operator=(const OcclusionTester&) = delete;

  /// True when the segment from `from` to `to` crosses no triangle before `to` (the last
  /// `tolerance_m` of it are not tested, so the surface point itself does not hide itself).
  /// Thread-safe.
  bool visible(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double tolerance_m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct WellImagedOptions {
  int min_views = 2;  ///< keyframes that must see a point
  double max_range_m =
      4.5;  ///< m, camera to point (the evaluate stage uses the water's visibility)
  double max_incidence_deg =
      80.0;  ///< deg between the surface normal and the direction to the camera
  double occlusion_tolerance_m = 0.02;  ///< m, see OcclusionTester::visible

  /// Throws OptionError naming the field.
  void check() const;
};

/// Per sample: how many views see it, counted up to `options.min_views` (the count stops
/// there: enough to decide). Parallel (OpenMP).
std::vector<uint8_t> countViews(const SurfaceSamples& samples, const std::vector<View>& views,
                                const OcclusionTester& occlusion, const WellImagedOptions& options);

}  // namespace auv::recon::evaluate
