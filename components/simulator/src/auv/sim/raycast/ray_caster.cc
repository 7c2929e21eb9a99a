#include "auv/sim/raycast/ray_caster.h"

#include <embree3/rtcore.h>

#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace auv::sim {
namespace {

std::string embreeError(RTCDevice device) {
  switch (rtcGetDeviceError(device)) {
    case RTC_ERROR_NONE:
      return "no error";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = srgbToLinear(i / 255.0f);
    return t;
  }();
  return table;
}

void fillRay(RTCRayHit& rh, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_min,
             float t_max) {
  rh.ray.org_x = o.x();
  rh.ray.org_y = o.y();
  rh.ray.org_z = o.z();
  rh.ray.dir_x = d.x();
  rh.ray.dir_y = d.y();
  rh.ray.dir_z = d.z();
  rh.ray.tnear = t_min;
  rh.ray.tfar = t_max;
  rh.ray.time = 0.0f;
  rh.ray.mask = static_cast<unsigned>(-1);  // Debian's Embree has ray masks: 0 hits nothing
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

RayHit toHit(const RTCRayHit& rh) {
  RayHit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.distance = rh.ray.tfar;
  hit.triangle = rh.hit.primID;
  hit.u = rh.hit.u;
  hit.v = rh.hit.v;
  Eigen::Vector3f n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const Eigen::Vector3f d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
  n.normalize();
  if (n.dot(d) > 0) n = -n;
  hit.normal = n;
  return hit;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3f closestOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                  const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  const float denom = 1.0f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct PointQueryResult {
  const Mesh* mesh;
  Eigen::Vector3f closest;
  uint32_t triangle = RayHit::kNoHit;
};

bool pointQueryCallback(RTCPointQueryFunctionArguments* args) {
  auto* result = static_cast<PointQueryResult*>(args->userPtr);
  const Eigen::Vector3i& t = result->mesh->triangles[args->primID];
  const Eigen::Vector3f p(args->query->x, args->query->y, args->query->z);
  const Eigen::Vector3f q = closestOnTriangle(
      p, result->mesh->vertices[t[0]], result->mesh->vertices[t[1]], result->mesh->vertices[t[2]]);
  const float d = (q - p).norm();
  if (d < args->query->radius) {
    args->query->radius = d;  // shrink the search: only closer triangles are visited next
    result->closest = q;
    result->triangle = args->primID;
    return true;
  }
  return false;
}

}  // namespace

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

struct RayCaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<Eigen::Vector3f> linear_vertex_colors;  // converted once: shading is hot
  std::optional<SurfaceDetail> detail;
};

RayCaster::RayCaster(const Mesh& mesh, const SurfaceDetailOptions& detail)
    : mesh_(mesh), impl_(std::make_unique<Impl>()) {
  if (mesh.triangles.empty()) throw std::runtime_error("RayCaster: the mesh has no triangles");
  if (detail.enabled()) impl_->detail.emplace(detail);
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // rtcSetNewGeometryBuffer pads the buffer as Embree's SIMD loads require.
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.vertices.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geometry);
    throw std::runtime_error("Embree: cannot allocate buffers: " + embreeError(impl_->device));
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = mesh.vertices[i][k];
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) indices[3 * i + k] = static_cast<unsigned>(mesh.triangles[i][k]);
  }
  impl_->linear_vertex_colors.reserve(mesh.vertex_colors.size());
  for (const Eigen::Vector3f& c : mesh.vertex_colors) {
    impl_->linear_vertex_colors.emplace_back(srgbToLinear(c.x()), srgbToLinear(c.y()),
                                             srgbToLinear(c.z()));
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(impl_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(impl_->scene);
  if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE) {
    throw std::runtime_error("Embree: cannot build the scene: " + embreeError(impl_->device));
  }
}

RayCaster::~RayCaster() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

RayHit RayCaster::cast(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_max,
                       float t_min) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  fillRay(rh, origin, direction, t_min, t_max);
  rtcIntersect1(impl_->scene, &context, &rh);
  return toHit(rh);
}

void RayCaster::castMany(const std::vector<Eigen::Vector3f>& origins,
                         const std::vector<Eigen::Vector3f>& directions, float t_max,
                         std::vector<RayHit>& hits, bool coherent) const {
  if (origins.size() != directions.size()) {
    throw std::invalid_argument("RayCaster::castMany: origins and directions differ in size");
  }
  hits.resize(origins.size());
  if (!coherent) {
    // Measured (sim_bench): for scattered rays Embree's stream path is ~4x slower than one
    // rtcIntersect1 per ray on this build, so only coherent bundles use streams.
    for (size_t i = 0; i < origins.size(); ++i) hits[i] = cast(origins[i], directions[i], t_max);
    return;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  constexpr size_t kChunk = 256;
  RTCRayHit stream[kChunk];
  for (size_t begin = 0; begin < origins.size(); begin += kChunk) {
    const size_t n = std::min(kChunk, origins.size() - begin);
    for (size_t i = 0; i < n; ++i) {
      fillRay(stream[i], origins[begin + i], directions[begin + i], 0.0f, t_max);
    }
    rtcIntersect1M(impl_->scene, &context, stream, static_cast<unsigned>(n), sizeof(RTCRayHit));
    for (size_t i = 0; i < n; ++i) hits[begin + i] = toHit(stream[i]);
  }
}

bool RayCaster::occluded(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                         float t_max) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  fillRay(rh, origin, direction, 0.0f, t_max);
  rtcOccluded1(impl_->scene, &context, &rh.ray);
  return rh.ray.tfar < 0.0f;  // Embree marks an occluded ray with tfar = -inf
}

Eigen::Vector3f RayCaster::pointAt(const RayHit& hit) const {
  const Eigen::Vector3i& t = mesh_.triangles[hit.triangle];
  return (1.0f - hit.u - hit.v) * mesh_.vertices[t[0]] + hit.u * mesh_.vertices[t[1]] +
         hit.v * mesh_.vertices[t[2]];
}

Eigen::Vector3f RayCaster::colorAt(const RayHit& hit) const {
  if (!hit.hit()) return Eigen::Vector3f::Zero();
  const Eigen::Vector3f color = meshColorAt(hit);
  return impl_->detail ? Eigen::Vector3f(color * impl_->detail->factor(pointAt(hit), hit.normal))
                       : color;
}

Eigen::Vector3f RayCaster::meshColorAt(const RayHit& hit) const {
  const float w0 = 1.0f - hit.u - hit.v;
  if (mesh_.hasTexture()) {
    const size_t base = 3 * static_cast<size_t>(hit.triangle);
    const Eigen::Vector2f uv = w0 * mesh_.triangle_uvs[base] +
                               hit.u * mesh_.triangle_uvs[base + 1] +
                               hit.v * mesh_.triangle_uvs[base + 2];
    // Bilinear lookup with wrap-around (repeat), in linear light.
    const cv::Mat& tex = mesh_.texture;
    const float x = (uv.x() - std::floor(uv.x())) * tex.cols - 0.5f;
    const float y = (uv.y() - std::floor(uv.y())) * tex.rows - 0.5f;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    const auto& lut = srgbTable();
    Eigen::Vector3f color = Eigen::Vector3f::Zero();
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) {
        const int px = ((x0 + dx) % tex.cols + tex.cols) % tex.cols;
        const int py = ((y0 + dy) % tex.rows + tex.rows) % tex.rows;
        const cv::Vec3b& bgr = tex.at<cv::Vec3b>(py, px);
        const float w = (dx ? fx : 1.0f - fx) * (dy ? fy : 1.0f - fy);
        color += w * Eigen::Vector3f(lut[bgr[2]], lut[bgr[1]], lut[bgr[0]]);
      }
    }
    return color;
  }
  if (mesh_.hasVertexColors()) {
    const Eigen::Vector3i& t = mesh_.triangles[hit.triangle];
    const auto& c = impl_->linear_vertex_colors;
    return w0 * c[t[0]] + hit.u * c[t[1]] + hit.v * c[t[2]];
  }
  return Eigen::Vector3f::Constant(0.5f);
}

bool RayCaster::closestPoint(const Eigen::Vector3f& point, float max_distance,
                             Eigen::Vector3f& closest, uint32_t& triangle) const {
  RTCPointQuery query;
  query.x = point.x();
  query.y = point.y();
  query.z = point.z();
  query.time = 0.0f;
  query.radius = max_distance;
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  PointQueryResult result{&mesh_, Eigen::Vector3f::Zero()};
  rtcPointQuery(impl_->scene, &query, &context, pointQueryCallback, &result);
  if (result.triangle == RayHit::kNoHit) return false;
  closest = result.closest;
  triangle = result.triangle;
  return true;
}

}  // namespace auv::sim
