#pragma once
// Ray casting against a world mesh with Embree 3 (Debian's build has ray masks enabled: every
// ray must carry mask = -1 or it hits nothing; see docs/library-notes.md). A RayCaster is immutable
// after construction and safe to use from many threads at once.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "auv/sim/world/mesh.h"
#include "auv/sim/world/surface_detail.h"

namespace auv::sim {

struct RayHit {
  float distance = std::numeric_limits<float>::infinity();  ///< m along the (unit) direction
  uint32_t triangle = kNoHit;                               ///< index into Mesh::triangles
  float u = 0, v = 0;               ///< barycentric coordinates of the hit in the triangle
  Eigen::Vector3f normal{0, 0, 0};  ///< unit geometric normal, facing the ray's origin

  static constexpr uint32_t kNoHit = 0xffffffffu;
  bool hit() const { return triangle != kNoHit; }
};

class RayCaster {
 public:
  /// Builds the acceleration structure; the mesh must outlive the caster (colours are read
  /// from it). `detail` adds fine albedo detail in colorAt (off by default). Throws
  /// std::runtime_error with Embree's error text on failure.
  explicit RayCaster(const Mesh& mesh, const SurfaceDetailOptions& detail = {});
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  /// Closest hit along origin + t * direction for t in [t_min, t_max]; `direction` unit.
  RayHit cast(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_max,
              float t_min = 0.0f) const;
  /// Many rays at once. `coherent`: the rays share an origin and nearby directions (a camera's
  /// primary rays) and go through Embree's ray streams, traced as packets; otherwise one by
  /// one, which is faster for scattered rays. Sizes must match.
  void castMany(const std::vector<Eigen::Vector3f>& origins,
                const std::vector<Eigen::Vector3f>& directions, float t_max,
                std::vector<RayHit>& hits, bool coherent = false) const;
  /// True if anything lies on the segment (for visibility / shadow tests).
  bool occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_max) const;

  /// Surface colour at a hit, linear RGB (texture bilinear, or interpolated vertex colours,
  /// converted from sRGB; times the surface detail when enabled).
  Eigen::Vector3f colorAt(const RayHit& hit) const;
  /// World position of a hit from its triangle and barycentrics.
  Eigen::Vector3f pointAt(const RayHit& hit) const;

  /// Closest point of the mesh to `point` within `max_distance` (for hull collisions); false if
  /// none. Uses Embree's point query.
  bool closestPoint(const Eigen::Vector3f& point, float max_distance, Eigen::Vector3f& closest,
                    uint32_t& triangle) const;

  const Mesh& mesh() const { return mesh_; }

 private:
  Eigen::Vector3f meshColorAt(const RayHit& hit) const;

  struct Impl;
  const Mesh& mesh_;
  std::unique_ptr<Impl> impl_;
};

/// sRGB (0..1) to linear, and back, per channel.
float srgbToLinear(float c);
float linearToSrgb(float c);

}  // namespace auv::sim
