#include "auv/sim/worldgen/shapes.h"

#include <algorithm>
#include <cmath>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/worldgen/noise.h"

namespace auv::sim::worldgen {
namespace {

using Eigen::Vector2f;
using Eigen::Vector3f;

constexpr float kPi = 3.14159265358979f;

// The ridge as a function of arc length: position and a tangent that turns smoothly through
// the polyline's vertices (so wall normals do not jump).
class Ridge {
 public:
  explicit Ridge(const std::vector<Vector2f>& points) : points_(points) {
    cumulative_.push_back(0.0f);
    for (size_t i = 1; i < points_.size(); ++i)
      cumulative_.push_back(cumulative_.back() + (points_[i] - points_[i - 1]).norm());
    for (size_t i = 0; i < points_.size(); ++i) {
      Vector2f t = Vector2f::Zero();
      if (i > 0) t += (points_[i] - points_[i - 1]).normalized();
      if (i + 1 < points_.size()) t += (points_[i + 1] - points_[i]).normalized();
      tangents_.push_back(t.norm() > 1e-6f ? Vector2f(t.normalized()) : Vector2f(1, 0));
    }
  }
  float length() const { return cumulative_.back(); }
  void at(float along, Vector2f& point, Vector2f& tangent) const {
    if (points_.size() == 1) {
      point = points_[0];
      tangent = Vector2f(1, 0);
      return;
    }
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), along);
    const size_t i =
        std::min<size_t>(std::max<ptrdiff_t>(it - cumulative_.begin(), 1) - 1, points_.size() - 2);
    const float span = cumulative_[i + 1] - cumulative_[i];
    const float f = span > 0.0f ? std::clamp((along - cumulative_[i]) / span, 0.0f, 1.0f) : 0.0f;
    point = points_[i] + f * (points_[i + 1] - points_[i]);
    const Vector2f t = (1.0f - f) * tangents_[i] + f * tangents_[i + 1];
    tangent = t.norm() > 1e-6f ? Vector2f(t.normalized()) : tangents_[i];
  }

 private:
  std::vector<Vector2f> points_;
  std::vector<float> cumulative_;
  std::vector<Vector2f> tangents_;
};

struct OutlineSample {
  Vector2f ridge_point;
  Vector2f normal;  // horizontal, outward
  float half_width;
};

Vector2f rightNormal(const Vector2f& t) { return {t.y(), -t.x()}; }
Vector2f leftNormal(const Vector2f& t) { return {-t.y(), t.x()}; }

// Counter-clockwise seen from above: along the right side, round the end, back along the left
// side, round the start. Samples of the two sides at the same ridge station use the same
// arc length, so the crest (where both collapse onto the ridge) closes exactly.
std::vector<OutlineSample> outline(const RockSpec& spec, const Ridge& ridge) {
  const float length = ridge.length();
  const int side_samples =
      length > 0.0f ? std::max(1, static_cast<int>(std::ceil(length / spec.spacing))) : 0;
  auto along = [&](int j) {
    return side_samples > 0 ? length * static_cast<float>(j) / side_samples : 0.0f;
  };
  std::vector<OutlineSample> samples;
  Vector2f point, tangent;
  auto cap = [&](float at, int from_side) {
    ridge.at(at, point, tangent);
    const float w_from = spec.half_width(at, from_side), w_to = spec.half_width(at, -from_side);
    const Vector2f n_from = from_side < 0 ? rightNormal(tangent) : leftNormal(tangent);
    const Vector2f forward = from_side < 0 ? tangent : Vector2f(-tangent);
    const int steps =
        std::max(6, static_cast<int>(std::ceil(kPi * 0.5f * (w_from + w_to) / spec.spacing)));
    for (int k = 0; k < steps; ++k) {
      const float theta = kPi * static_cast<float>(k) / steps;
      const float blend = 0.5f * (1.0f - std::cos(theta));
      samples.push_back({point, std::cos(theta) * n_from + std::sin(theta) * forward,
                         w_from + blend * (w_to - w_from)});
    }
  };
  for (int j = 0; j < side_samples; ++j) {
    ridge.at(along(j), point, tangent);
    samples.push_back({point, rightNormal(tangent), spec.half_width(along(j), -1)});
  }
  cap(length, -1);
  for (int j = side_samples; j > 0; --j) {
    ridge.at(along(j), point, tangent);
    samples.push_back({point, leftNormal(tangent), spec.half_width(along(j), +1)});
  }
  cap(0.0f, +1);
  return samples;
}

// Rows of the wall profile (width fraction, height) evenly spaced along the profile curve of
// a wall `reference_width` wide, with the curve's tangent (d fraction, d z) per row.
struct ProfileRow {
  float fraction, z, d_fraction, d_z;
};

std::vector<ProfileRow> profileRows(const RockSpec& spec, float reference_width) {
  const float crest_start = spec.top_z - spec.crest * (spec.top_z - spec.seabed_z);
  std::vector<Vector2f> dense;  // (fraction, z)
  if (spec.width_profile) {
    const int samples = 256;
    for (int k = 0; k <= samples; ++k) {
      const float z =
          spec.bottom_z + (spec.top_z - spec.bottom_z) * static_cast<float>(k) / samples;
      dense.emplace_back(spec.width_profile(z), z);
    }
  } else {
    dense.emplace_back(rockWidthFraction(spec, spec.bottom_z), spec.bottom_z);
    dense.emplace_back(1.0f - spec.taper, crest_start);
    const int crest_samples = 64;
    for (int k = 1; k <= crest_samples; ++k) {
      const float alpha = 0.5f * kPi * static_cast<float>(k) / crest_samples;
      dense.emplace_back((1.0f - spec.taper) * std::cos(alpha),
                         crest_start + (spec.top_z - crest_start) * std::sin(alpha));
    }
  }
  dense.back() = Vector2f(0.0f, spec.top_z);
  std::vector<float> cumulative{0.0f};
  for (size_t i = 1; i < dense.size(); ++i) {
    const Vector2f step = dense[i] - dense[i - 1];
    cumulative.push_back(cumulative.back() + std::hypot(step.x() * reference_width, step.y()));
  }
  const int rows = std::max(3, static_cast<int>(std::ceil(cumulative.back() / spec.spacing)) + 1);
  std::vector<Vector2f> resampled;
  size_t i = 0;
  for (int r = 0; r < rows; ++r) {
    const float s = cumulative.back() * static_cast<float>(r) / (rows - 1);
    while (i + 2 < dense.size() && cumulative[i + 1] < s) ++i;
    const float span = cumulative[i + 1] - cumulative[i];
    const float f = span > 0.0f ? std::clamp((s - cumulative[i]) / span, 0.0f, 1.0f) : 0.0f;
    resampled.push_back(dense[i] + f * (dense[i + 1] - dense[i]));
  }
  resampled.back() = Vector2f(0.0f, spec.top_z);
  std::vector<ProfileRow> result;
  for (int r = 0; r < rows; ++r) {
    const Vector2f d = resampled[std::min(r + 1, rows - 1)] - resampled[std::max(r - 1, 0)];
    result.push_back({resampled[r].x(), resampled[r].y(), d.x(), d.y()});
  }
  return result;
}

// Displacement in [-1, 1]: lumps of several metres, crags (ridged noise) and small knobs.
float rockDisplacement(const GradientNoise& noise, const Vector3f& p) {
  const float lumps = noise.fbm(p, 7.0f, 3);
  const float crags = 2.0f * noise.ridged(p + Vector3f(7.7f, 3.1f, -2.2f), 2.2f, 2) - 1.0f;
  const float knobs = noise.fbm(p + Vector3f(-4.4f, 9.9f, 1.7f), 0.8f, 2);
  return std::clamp(0.55f * lumps + 0.30f * crags + 0.15f * knobs, -1.0f, 1.0f);
}

}  // namespace

float rockWidthFraction(const RockSpec& spec, float z) {
  if (spec.width_profile) return z >= spec.top_z ? 0.0f : std::max(0.0f, spec.width_profile(z));
  const float crest_start = spec.top_z - spec.crest * (spec.top_z - spec.seabed_z);
  if (z <= crest_start)
    return 1.0f - spec.taper * (z - spec.seabed_z) / (crest_start - spec.seabed_z);
  if (z >= spec.top_z) return 0.0f;
  const float t = (z - crest_start) / (spec.top_z - crest_start);
  return (1.0f - spec.taper) * std::sqrt(std::max(0.0f, 1.0f - t * t));
}

SurfaceGrid buildRock(const RockSpec& spec) {
  if (spec.ridge.empty() || !spec.half_width || !(spec.top_z > spec.seabed_z) ||
      !(spec.seabed_z > spec.bottom_z) || !(spec.spacing > 0.0f) || spec.crest <= 0.0f ||
      spec.crest >= 1.0f || spec.taper < 0.0f || spec.taper >= 1.0f) {
    throw ConfigError("worldgen: invalid rock specification");
  }
  const Ridge ridge(spec.ridge);
  const std::vector<OutlineSample> columns = outline(spec, ridge);
  float mean_width = 0.0f;
  for (const OutlineSample& s : columns) mean_width += s.half_width;
  mean_width /= static_cast<float>(columns.size());
  const std::vector<ProfileRow> rows = profileRows(spec, mean_width);

  SurfaceGrid grid(static_cast<int>(rows.size()), static_cast<int>(columns.size()), true,
                   Material::ROCK, spec.texel_size);
  std::vector<Vector3f> displacement_normals(grid.points.size());
  const GradientNoise noise(spec.seed);
  for (int r = 0; r < grid.rows; ++r) {
    const ProfileRow& row = rows[r];
    const bool crest_line = r == grid.rows - 1;
    for (int c = 0; c < grid.cols; ++c) {
      const OutlineSample& col = columns[c];
      const Vector2f horizontal = col.ridge_point + col.normal * (col.half_width * row.fraction);
      const Vector3f base(horizontal.x(), horizontal.y(), row.z);
      // Normal of the undisplaced wall: in the plane of the outward normal and the vertical.
      Vector3f normal = crest_line ? Vector3f::UnitZ()
                                   : Vector3f(col.normal.x() * row.d_z, col.normal.y() * row.d_z,
                                              -col.half_width * row.d_fraction);
      normal = normal.norm() > 1e-9f ? Vector3f(normal.normalized()) : Vector3f::UnitZ();
      const size_t i = static_cast<size_t>(r) * grid.cols + c;
      displacement_normals[i] = normal;
      const float amplitude = spec.roughness_at ? spec.roughness_at(horizontal) : spec.roughness;
      grid.points[i] = base + normal * (amplitude * rockDisplacement(noise, base));
    }
  }
  computeNormals(grid, &displacement_normals);
  return grid;
}

float distanceToPolyline(const std::vector<Vector2f>& line, const Vector2f& point) {
  if (line.empty()) return std::numeric_limits<float>::infinity();
  float best = (line[0] - point).norm();
  for (size_t i = 1; i < line.size(); ++i) {
    const Vector2f a = line[i - 1], ab = line[i] - a;
    const float t = ab.squaredNorm() > 0.0f
                        ? std::clamp((point - a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f)
                        : 0.0f;
    best = std::min(best, (a + t * ab - point).norm());
  }
  return best;
}

float seabedHeight(const SeabedSpec& spec, float x, float y) {
  const GradientNoise noise(spec.seed);
  return spec.mean_z + spec.undulation * noise.fbm(Vector3f(x, y, 0.5f), 18.0f, 3);
}

SurfaceGrid buildSeabed(const SeabedSpec& spec) {
  const Vector2f size = spec.area.sizes();
  if (!(size.minCoeff() > 0.0f) || !(spec.spacing > 0.0f))
    throw ConfigError("worldgen: invalid seabed specification");
  const int quads_x = std::max(1, static_cast<int>(std::ceil(size.x() / spec.spacing)));
  const int quads_y = std::max(1, static_cast<int>(std::ceil(size.y() / spec.spacing)));
  // Rows along y, columns along x: d/dc x d/dr = x x y = up.
  SurfaceGrid grid(quads_y + 1, quads_x + 1, false, Material::SAND, spec.texel_size);
  for (int r = 0; r <= quads_y; ++r) {
    for (int c = 0; c <= quads_x; ++c) {
      const float x = spec.area.min().x() + size.x() * static_cast<float>(c) / quads_x;
      const float y = spec.area.min().y() + size.y() * static_cast<float>(r) / quads_y;
      grid.at(r, c) = Vector3f(x, y, seabedHeight(spec, x, y));
    }
  }
  if (spec.covered) {
    std::vector<uint8_t> point_covered(grid.points.size());
    for (size_t i = 0; i < grid.points.size(); ++i)
      point_covered[i] = spec.covered(grid.points[i].head<2>()) ? 1 : 0;
    auto hiddenAt = [&](int r, int c) {
      return point_covered[static_cast<size_t>(r) * grid.cols + c] != 0;
    };
    grid.quad_enabled.assign(static_cast<size_t>(quads_y) * quads_x, 1);
    for (int r = 0; r < quads_y; ++r) {
      for (int c = 0; c < quads_x; ++c) {
        if (hiddenAt(r, c) && hiddenAt(r, c + 1) && hiddenAt(r + 1, c) && hiddenAt(r + 1, c + 1))
          grid.quad_enabled[static_cast<size_t>(r) * quads_x + c] = 0;
      }
    }
  }
  computeNormals(grid);
  return grid;
}

std::vector<SurfaceGrid> buildBlock(const Eigen::AlignedBox3f& box, float spacing,
                                    Material material, float texel_size) {
  const Vector3f lo = box.min(), hi = box.max(), size = box.sizes();
  const Vector3f up(0, 0, size.z());
  std::vector<SurfaceGrid> faces;
  // Walls: columns along up x outward normal, rows up.
  faces.push_back(
      planarGrid({hi.x(), lo.y(), lo.z()}, {0, size.y(), 0}, up, spacing, material, texel_size));
  faces.push_back(
      planarGrid({lo.x(), hi.y(), lo.z()}, {0, -size.y(), 0}, up, spacing, material, texel_size));
  faces.push_back(
      planarGrid({hi.x(), hi.y(), lo.z()}, {-size.x(), 0, 0}, up, spacing, material, texel_size));
  faces.push_back(
      planarGrid({lo.x(), lo.y(), lo.z()}, {size.x(), 0, 0}, up, spacing, material, texel_size));
  faces.push_back(planarGrid({lo.x(), lo.y(), hi.z()}, {size.x(), 0, 0}, {0, size.y(), 0}, spacing,
                             material, texel_size));
  return faces;
}

}  // namespace auv::sim::worldgen
