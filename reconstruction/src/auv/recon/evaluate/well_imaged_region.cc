#include "auv/recon/evaluate/well_imaged_region.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/TriangleMesh.h>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::evaluate {
namespace {

/// SplitMix64: one well-mixed seed per triangle, so a triangle's samples do not depend on
/// which other triangles are sampled.
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

Eigen::MatrixXd toMatrix(const std::vector<Eigen::Vector3d>& points) {
  Eigen::MatrixXd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

}  // namespace

SurfaceSamples sampleSurface(const open3d::geometry::TriangleMesh& mesh, double spacing_m,
                             uint64_t seed, const std::vector<size_t>* triangles) {
  if (!(spacing_m > 0)) throw std::invalid_argument("sampleSurface: spacing must be > 0");
  SurfaceSamples samples;
  const double per_area = 1.0 / (spacing_m * spacing_m);
  const size_t count = triangles ? triangles->size() : mesh.triangles_.size();
  for (size_t k = 0; k < count; ++k) {
    const size_t t = triangles ? (*triangles)[k] : k;
    const Eigen::Vector3i& tri = mesh.triangles_[t];
    const Eigen::Vector3d& a = mesh.vertices_[tri(0)];
    const Eigen::Vector3d& b = mesh.vertices_[tri(1)];
    const Eigen::Vector3d& c = mesh.vertices_[tri(2)];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double area = 0.5 * cross.norm();
    if (!(area > 0)) continue;
    const Eigen::Vector3d normal = cross.normalized();
    std::mt19937_64 rng(mix(seed ^ mix(t)));
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double expected = area * per_area;
    size_t n = static_cast<size_t>(expected);
    if (uniform(rng) < expected - static_cast<double>(n)) ++n;
    for (size_t i = 0; i < n; ++i) {
      double u = uniform(rng), v = uniform(rng);
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      samples.points.push_back(a + u * (b - a) + v * (c - a));
      samples.normals.push_back(normal);
    }
  }
  return samples;
}

std::vector<size_t> trianglesNear(const open3d::geometry::TriangleMesh& mesh,
                                  const std::vector<Eigen::Vector3d>& centers, double distance_m) {
  std::vector<size_t> near;
  if (centers.empty()) return near;
  // Open3D 0.16 keeps referring to the matrix it was built from: it must outlive the tree.
  const Eigen::MatrixXd tree_data = toMatrix(centers);
  const open3d::geometry::KDTreeFlann tree(tree_data);
  std::vector<int> index(1);
  std::vector<double> distance2(1);
  for (size_t t = 0; t < mesh.triangles_.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles_[t];
    const Eigen::Vector3d centroid =
        (mesh.vertices_[tri(0)] + mesh.vertices_[tri(1)] + mesh.vertices_[tri(2)]) / 3.0;
    double radius = 0;
    for (int j = 0; j < 3; ++j) {
      radius = std::max(radius, (mesh.vertices_[tri(j)] - centroid).norm());
    }
    if (tree.SearchKNN(centroid, 1, index, distance2) > 0 &&
        std::sqrt(distance2[0]) <= distance_m + radius) {
      near.push_back(t);
    }
  }
  return near;
}

struct OcclusionTester::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

OcclusionTester::OcclusionTester(const open3d::geometry::TriangleMesh& mesh)
    : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.vertices_.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles_.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geometry);
    throw std::runtime_error("Embree: cannot allocate the mesh buffers");
  }
  for (size_t i = 0; i < mesh.vertices_.size(); ++i) {
    for (int j = 0; j < 3; ++j) vertices[3 * i + j] = static_cast<float>(mesh.vertices_[i](j));
  }
  for (size_t i = 0; i < mesh.triangles_.size(); ++i) {
    for (int j = 0; j < 3; ++j) indices[3 * i + j] = static_cast<unsigned>(mesh.triangles_[i](j));
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(impl_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(impl_->scene);
  if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE) {
    throw std::runtime_error("Embree: cannot build the scene");
  }
}

OcclusionTester::~OcclusionTester() = default;

bool OcclusionTester::visible(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                              double tolerance_m) const {
  const Eigen::Vector3d d = to - from;
  const double length = d.norm();
  if (length <= tolerance_m) return true;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = static_cast<float>(from.x());
  ray.org_y = static_cast<float>(from.y());
  ray.org_z = static_cast<float>(from.z());
  ray.dir_x = static_cast<float>(d.x() / length);
  ray.dir_y = static_cast<float>(d.y() / length);
  ray.dir_z = static_cast<float>(d.z() / length);
  ray.tnear = 0.0f;
  ray.tfar = static_cast<float>(length - tolerance_m);
  ray.time = 0.0f;
  ray.mask = static_cast<unsigned>(-1);  // Debian's Embree is built with ray masks
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar >= 0.0f;  // Embree sets tfar to -inf when something is hit
}

void WellImagedOptions::check() const {
  AUV_RECON_CHECK_OPTION(min_views >= 1 && min_views <= 255, min_views, "must be in [1, 255]");
  AUV_RECON_CHECK_OPTION(max_range_m > 0 && std::isfinite(max_range_m), max_range_m,
                         "must be > 0 m");
  AUV_RECON_CHECK_OPTION(max_incidence_deg > 0 && max_incidence_deg <= 90, max_incidence_deg,
                         "must be in (0, 90] deg");
  AUV_RECON_CHECK_OPTION(occlusion_tolerance_m >= 0, occlusion_tolerance_m, "must be >= 0 m");
}

std::vector<uint8_t> countViews(const SurfaceSamples& samples, const std::vector<View>& views,
                                const OcclusionTester& occlusion,
                                const WellImagedOptions& options) {
  options.check();
  std::vector<uint8_t> counts(samples.size(), 0);
  if (views.empty() || samples.size() == 0) return counts;
  std::vector<Eigen::Vector3d> centers;
  // A lens's polynomial can fold far-off-axis points back into the image: accept only points
  // within the normalised radius the image corners reach (plus a margin).
  std::vector<double> max_radius2;
  for (const View& view : views) {
    centers.push_back(view.center());
    double r2 = 0;
    const scene::Camera& c = view.camera;
    for (double u : {-0.5, c.width - 0.5}) {
      for (double v : {-0.5, c.height - 0.5}) {
        r2 = std::max(r2, c.pixelToNormalized(Eigen::Vector2d(u, v)).squaredNorm());
      }
    }
    max_radius2.push_back(1.1 * 1.1 * r2);
  }
  // Open3D 0.16 keeps referring to the matrix it was built from: it must outlive the tree.
  const Eigen::MatrixXd tree_data = toMatrix(centers);
  const open3d::geometry::KDTreeFlann tree(tree_data);
  const double min_cos = std::cos(options.max_incidence_deg * M_PI / 180.0);
  const double range2 = options.max_range_m * options.max_range_m;

#pragma omp parallel for schedule(dynamic, 256)
  for (int64_t i = 0; i < static_cast<int64_t>(samples.size()); ++i) {
    const Eigen::Vector3d& p = samples.points[i];
    const Eigen::Vector3d& n = samples.normals[i];
    std::vector<int> candidates;
    std::vector<double> distance2;
    tree.SearchRadius(p, options.max_range_m, candidates, distance2);
    int seen = 0;
    for (size_t k = 0; k < candidates.size() && seen < options.min_views; ++k) {
      const View& view = views[candidates[k]];
      const Eigen::Vector3d to_camera = centers[candidates[k]] - p;
      const double d2 = to_camera.squaredNorm();
      if (d2 > range2 || d2 <= 0) continue;
      if (std::abs(n.dot(to_camera)) < min_cos * std::sqrt(d2)) continue;
      const Eigen::Vector3d pc = view.rotation_cw * p + view.translation_cw;
      if (pc.z() <= 1e-6) continue;
      const Eigen::Vector2d normalized(pc.x() / pc.z(), pc.y() / pc.z());
      if (normalized.squaredNorm() > max_radius2[candidates[k]]) continue;
      if (!view.camera.inImage(view.camera.project(pc))) continue;
      if (!occlusion.visible(centers[candidates[k]], p, options.occlusion_tolerance_m)) continue;
      ++seen;
    }
    counts[i] = static_cast<uint8_t>(seen);
  }
  return counts;
}

}  // namespace auv::recon::evaluate
