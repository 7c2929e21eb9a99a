#include "auv/sim/world/site_changes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

#include "auv/sim/world/rock.h"

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::string describe(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return out.str();
}

/// 1 inside 70 % of the radius, a cosine down to 0 at the radius: a patch with a plateau (the
/// stated thickness or colour) and no step at its rim.
double plateauWeight(double distance, double radius) {
  const double inner = 0.7 * radius;
  if (distance <= inner) return 1.0;
  if (distance >= radius) return 0.0;
  return 0.5 * (1.0 + std::cos(M_PI * (distance - inner) / (radius - inner)));
}

Eigen::Vector3f triangleNormal(const Mesh& mesh, const Eigen::Vector3i& t) {
  const Eigen::Vector3f& a = mesh.vertices[t[0]];
  return (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);  // length = 2 * area
}

/// Splits (1 -> 4, shared edge midpoints) every triangle that comes within its own longest edge
/// of the sphere until its edges are at most `max_edge`. A triangle left whole next to a split
/// one has all its corners beyond the sphere by its longest edge, so the midpoint on their
/// shared edge lies outside the sphere, where the patch weight is 0: displacing the patch opens
/// no crack.
void refineNear(Mesh& mesh, const Eigen::Vector3f& center, float radius, float max_edge) {
  const bool textured = mesh.hasTexture(), coloured = mesh.hasVertexColors();
  for (int round = 0; round < 12; ++round) {
    std::vector<Eigen::Vector3i> triangles;
    std::vector<Eigen::Vector2f> uvs;
    std::map<std::pair<int, int>, int> midpoints;
    bool split_any = false;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      mesh.vertices.push_back(0.5f * (mesh.vertices[a] + mesh.vertices[b]));
      if (coloured)
        mesh.vertex_colors.push_back(0.5f * (mesh.vertex_colors[a] + mesh.vertex_colors[b]));
      const int index = static_cast<int>(mesh.vertices.size()) - 1;
      midpoints.emplace(key, index);
      return index;
    };
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
      const Eigen::Vector3i t = mesh.triangles[i];
      float longest = 0.0f, nearest = std::numeric_limits<float>::max();
      for (int k = 0; k < 3; ++k) {
        longest = std::max(longest, (mesh.vertices[t[k]] - mesh.vertices[t[(k + 1) % 3]]).norm());
        nearest = std::min(nearest, (mesh.vertices[t[k]] - center).norm());
      }
      if (longest <= max_edge || nearest > radius + longest) {
        triangles.push_back(t);
        if (textured)
          uvs.insert(uvs.end(), &mesh.triangle_uvs[3 * i], &mesh.triangle_uvs[3 * i + 3]);
        continue;
      }
      split_any = true;
      const int m01 = midpoint(t[0], t[1]), m12 = midpoint(t[1], t[2]), m20 = midpoint(t[2], t[0]);
      triangles.insert(triangles.end(),
                       {Eigen::Vector3i(t[0], m01, m20), Eigen::Vector3i(m01, t[1], m12),
                        Eigen::Vector3i(m20, m12, t[2]), Eigen::Vector3i(m01, m12, m20)});
      if (textured) {
        const Eigen::Vector2f* c = &mesh.triangle_uvs[3 * i];
        const Eigen::Vector2f u01 = 0.5f * (c[0] + c[1]), u12 = 0.5f * (c[1] + c[2]),
                              u20 = 0.5f * (c[2] + c[0]);
        uvs.insert(uvs.end(), {c[0], u01, u20, u01, c[1], u12, u20, u12, c[2], u01, u12, u20});
      }
    }
    mesh.triangles = std::move(triangles);
    if (textured) mesh.triangle_uvs = std::move(uvs);
    if (!split_any) return;
  }
}

/// Triangles with a corner inside the sphere.
std::vector<size_t> trianglesTouching(const Mesh& mesh, const Eigen::Vector3f& center,
                                      float radius) {
  std::vector<size_t> touching;
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if ((mesh.vertices[mesh.triangles[i][k]] - center).norm() < radius) {
        touching.push_back(i);
        break;
      }
    }
  }
  return touching;
}

float edgeFor(double radius) { return static_cast<float>(std::clamp(radius / 10.0, 0.03, 0.1)); }

/// Grows (or erodes) the surface inside the sphere by `thickness` along the patch's mean
/// normal (one direction for every vertex: vertices of separate parts that coincide move
/// together, so seams stay closed). Returns the signed volume between the two surfaces.
double growPatch(Mesh& mesh, const SiteChange& change, const std::string& where) {
  const Eigen::Vector3f center = change.center.cast<float>();
  const float radius = static_cast<float>(change.radius);
  refineNear(mesh, center, radius, edgeFor(change.radius));
  const std::vector<size_t> touching = trianglesTouching(mesh, center, radius);
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  for (size_t i : touching) normal += triangleNormal(mesh, mesh.triangles[i]);
  if (touching.empty() || normal.norm() == 0.0f)
    throw ConfigError(where + ".center: no surface within radius " + std::to_string(change.radius) +
                      " m of " + describe(change.center));
  normal.normalize();
  std::vector<float> weight(mesh.vertices.size(), 0.0f);
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    weight[v] = static_cast<float>(plateauWeight((mesh.vertices[v] - center).norm(), radius));
  // Volume before moving: area projected on the direction times the mean displacement.
  double volume = 0.0;
  for (size_t i : touching) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    const double mean_weight = (weight[t[0]] + weight[t[1]] + weight[t[2]]) / 3.0;
    volume += 0.5 * triangleNormal(mesh, t).dot(normal) * mean_weight * change.thickness;
  }
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (weight[v] > 0.0f)
      mesh.vertices[v] += weight[v] * static_cast<float>(change.thickness) * normal;
  return volume;
}

/// Blends the surface colour inside the sphere towards `color` (texels of a textured mesh, or
/// the vertex colours after refining the patch).
void changeAlbedo(Mesh& mesh, const SiteChange& change) {
  const Eigen::Vector3f center = change.center.cast<float>();
  const float radius = static_cast<float>(change.radius);
  const Eigen::Vector3f target = change.color.cast<float>();
  if (!mesh.hasTexture()) {
    refineNear(mesh, center, radius, edgeFor(change.radius));
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      const float w = static_cast<float>(change.strength *
                                         plateauWeight((mesh.vertices[v] - center).norm(), radius));
      if (w > 0.0f) mesh.vertex_colors[v] = (1.0f - w) * mesh.vertex_colors[v] + w * target;
    }
    return;
  }
  mesh.texture = mesh.texture.clone();  // copies of the mesh (the earlier visit) keep theirs
  const cv::Vec3f bgr(target.z() * 255.0f, target.y() * 255.0f, target.x() * 255.0f);
  const Eigen::Vector2f pixels(static_cast<float>(mesh.texture.cols),
                               static_cast<float>(mesh.texture.rows));
  for (size_t i : trianglesTouching(mesh, center, radius)) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    Eigen::Vector2f uv[3];
    for (int k = 0; k < 3; ++k)
      uv[k] = mesh.triangle_uvs[3 * i + k].cwiseProduct(pixels) - Eigen::Vector2f(0.5f, 0.5f);
    const Eigen::Vector2f low = uv[0].cwiseMin(uv[1]).cwiseMin(uv[2]);
    const Eigen::Vector2f high = uv[0].cwiseMax(uv[1]).cwiseMax(uv[2]);
    const float area =
        (uv[1] - uv[0]).x() * (uv[2] - uv[0]).y() - (uv[1] - uv[0]).y() * (uv[2] - uv[0]).x();
    if (std::abs(area) < 1e-9f) continue;
    for (int y = std::max(0, int(std::floor(low.y())));
         y <= std::min(mesh.texture.rows - 1, int(std::ceil(high.y()))); ++y) {
      for (int x = std::max(0, int(std::floor(low.x())));
           x <= std::min(mesh.texture.cols - 1, int(std::ceil(high.x()))); ++x) {
        // Barycentrics of the texel centre in the triangle's texture footprint.
        const Eigen::Vector2f p(static_cast<float>(x), static_cast<float>(y));
        const float b1 =
            ((p - uv[0]).x() * (uv[2] - uv[0]).y() - (p - uv[0]).y() * (uv[2] - uv[0]).x()) / area;
        const float b2 =
            ((uv[1] - uv[0]).x() * (p - uv[0]).y() - (uv[1] - uv[0]).y() * (p - uv[0]).x()) / area;
        if (b1 < -0.02f || b2 < -0.02f || b1 + b2 > 1.02f) continue;
        const Eigen::Vector3f point = (1 - b1 - b2) * mesh.vertices[t[0]] +
                                      b1 * mesh.vertices[t[1]] + b2 * mesh.vertices[t[2]];
        const double w = change.strength * plateauWeight((point - center).norm(), radius);
        if (w <= 0.0) continue;
        cv::Vec3b& texel = mesh.texture.at<cv::Vec3b>(y, x);
        for (int c = 0; c < 3; ++c)
          texel[c] = cv::saturate_cast<uchar>((1.0 - w) * texel[c] + w * bgr[c]);
      }
    }
  }
}

/// Removes (or moves) the loose rocks wholly inside the sphere. Returns the bounding spheres of
/// where they were and where they are now.
std::vector<ChangeSupport> removeOrMove(Mesh& mesh, const SiteChange& change,
                                        const std::string& where) {
  const std::vector<std::vector<int>> rocks = looseRocksWithin(mesh, change.center, change.radius);
  if (rocks.empty())
    throw ConfigError(where +
                      ".center: no loose rock (a part of the mesh connected to nothing "
                      "else) lies wholly within radius " +
                      std::to_string(change.radius) + " m of " + describe(change.center) +
                      ": remove and move act on separate boulders or blocks");
  std::vector<char> selected(mesh.triangles.size(), 0);
  std::vector<int> vertices;
  for (const std::vector<int>& rock : rocks) {
    for (int t : rock) {
      selected[t] = 1;
      for (int k = 0; k < 3; ++k) vertices.push_back(mesh.triangles[t][k]);
    }
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int v : vertices) centroid += mesh.vertices[v].cast<double>();
  centroid /= static_cast<double>(vertices.size());
  double extent = 0.0;
  for (int v : vertices)
    extent = std::max(extent, (mesh.vertices[v].cast<double>() - centroid).norm());
  std::vector<ChangeSupport> supports{{centroid, extent}};

  if (change.type == SiteChangeType::kMove) {
    const Eigen::Matrix3f turn =
        Eigen::AngleAxisf(static_cast<float>(change.yaw_deg * kDeg), Eigen::Vector3f::UnitZ())
            .toRotationMatrix();
    const Eigen::Vector3f pivot = centroid.cast<float>();
    for (int v : vertices)
      mesh.vertices[v] =
          turn * (mesh.vertices[v] - pivot) + pivot + change.translation.cast<float>();
    supports.push_back({centroid + change.translation, extent});
    return supports;
  }
  std::vector<Eigen::Vector3i> kept;
  std::vector<Eigen::Vector2f> kept_uvs;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (selected[t]) continue;
    kept.push_back(mesh.triangles[t]);
    if (mesh.hasTexture())
      kept_uvs.insert(kept_uvs.end(), &mesh.triangle_uvs[3 * t], &mesh.triangle_uvs[3 * t + 3]);
  }
  mesh.triangles = std::move(kept);
  if (mesh.hasTexture()) mesh.triangle_uvs = std::move(kept_uvs);
  return supports;
}

SiteChangeType parseType(const YamlSection& entry) {
  std::string type;
  entry.read("type", type);
  const std::map<std::string, SiteChangeType> types{{"add", SiteChangeType::kAdd},
                                                    {"remove", SiteChangeType::kRemove},
                                                    {"move", SiteChangeType::kMove},
                                                    {"grow", SiteChangeType::kGrow},
                                                    {"albedo", SiteChangeType::kAlbedo}};
  const auto it = types.find(type);
  if (it == types.end())
    entry.fail("type", "expected add, remove, move, grow or albedo, got '" + type + "'");
  return it->second;
}

}  // namespace

const char* toString(SiteChangeType type) {
  switch (type) {
    case SiteChangeType::kAdd:
      return "add";
    case SiteChangeType::kRemove:
      return "remove";
    case SiteChangeType::kMove:
      return "move";
    case SiteChangeType::kGrow:
      return "grow";
    case SiteChangeType::kAlbedo:
      return "albedo";
  }
  return "?";
}

std::vector<SiteChange> readSiteChanges(const YamlSection& root) {
  std::vector<SiteChange> changes;
  for (const YamlSection& entry : root.childList("changes")) {
    entry.rejectUnknownKeys({"name", "type", "center", "position", "radius", "size", "translation",
                             "yaw_deg", "thickness", "color", "strength", "seed"});
    SiteChange c;
    c.name = "change" + std::to_string(changes.size() + 1);
    entry.read("name", c.name);
    if (!entry.has("type")) entry.fail("type", "missing: add, remove, move, grow or albedo");
    c.type = parseType(entry);
    const bool add = c.type == SiteChangeType::kAdd;
    const char* where_key = add ? "position" : "center";
    if (!entry.has(where_key))
      entry.fail(where_key, std::string("missing: ") +
                                (add ? "the point [x, y, z] (m NED) the new rock sits on"
                                     : "the centre [x, y, z] (m NED) of the changed place"));
    entry.rejectUnknownKeys(
        add ? std::vector<std::string>{"name", "type", "position", "size", "yaw_deg", "seed"}
            : std::vector<std::string>{"name", "type", "center", "radius", "translation", "yaw_deg",
                                       "thickness", "color", "strength"});
    entry.read(where_key, c.center);
    entry.read("radius", c.radius, 0.05, 50.0);
    entry.read("size", c.size, 0.05, 20.0);
    entry.read("yaw_deg", c.yaw_deg, -360.0, 360.0);
    entry.read("seed", c.seed, 0);
    entry.read("strength", c.strength, 0.0, 1.0);
    entry.read("color", c.color, 0.0, 1.0);
    if (c.type == SiteChangeType::kMove && !entry.has("translation"))
      entry.fail("translation", "missing: how far [dx, dy, dz] (m) the rock moved");
    entry.read("translation", c.translation);
    if (c.type == SiteChangeType::kGrow) {
      if (!entry.has("thickness"))
        entry.fail("thickness", "missing: m of growth (> 0) or erosion (< 0)");
      entry.read("thickness", c.thickness, -0.5 * c.radius, 0.5 * c.radius);
      if (c.thickness == 0.0) entry.fail("thickness", "must not be 0 (m; > 0 grows, < 0 erodes)");
    }
    if (c.type == SiteChangeType::kAlbedo && !(c.strength > 0.0))
      entry.fail("strength", "must be > 0 (0 changes nothing)");
    for (const SiteChange& earlier : changes)
      if (earlier.name == c.name) entry.fail("name", "'" + c.name + "' is used twice");
    changes.push_back(c);
  }
  return changes;
}

std::vector<std::vector<int>> looseRocksWithin(const Mesh& mesh, const Eigen::Vector3d& center,
                                               double radius) {
  const Eigen::Vector3f c = center.cast<float>();
  const float r = static_cast<float>(radius);
  std::vector<char> inside(mesh.vertices.size(), 0), touched_outside(mesh.vertices.size(), 0);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) inside[v] = (mesh.vertices[v] - c).norm() <= r;
  // Union-find over the vertices of triangles wholly inside.
  std::vector<int> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<int> candidates;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (inside[tri[0]] && inside[tri[1]] && inside[tri[2]]) {
      candidates.push_back(static_cast<int>(t));
      parent[find(tri[1])] = find(tri[0]);
      parent[find(tri[2])] = find(tri[0]);
    } else {
      for (int k = 0; k < 3; ++k) touched_outside[tri[k]] = 1;
    }
  }
  // A part is loose when no triangle reaching outside the sphere shares a vertex with it.
  std::map<int, std::vector<int>> parts;
  std::map<int, bool> attached;
  for (int t : candidates) {
    const int root = find(mesh.triangles[t][0]);
    parts[root].push_back(t);
    for (int k = 0; k < 3; ++k)
      attached[root] = attached[root] || touched_outside[mesh.triangles[t][k]];
  }
  std::vector<std::vector<int>> loose;
  for (auto& [root, triangles] : parts)
    if (!attached[root]) loose.push_back(std::move(triangles));
  return loose;
}

std::vector<AppliedChange> applySiteChanges(Mesh& mesh, const std::vector<SiteChange>& changes,
                                            const std::string& file) {
  std::vector<AppliedChange> applied;
  for (size_t i = 0; i < changes.size(); ++i) {
    const SiteChange& change = changes[i];
    const std::string where = file + ": changes[" + std::to_string(i) + "] (" + change.name + ")";
    AppliedChange result{change, {}, 0.0};
    switch (change.type) {
      case SiteChangeType::kAdd: {
        const Mesh rock = makeRock(change.center, change.size, change.yaw_deg, change.seed, mesh);
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3f& v : rock.vertices) centroid += v.cast<double>();
        centroid /= static_cast<double>(rock.vertices.size());
        double extent = 0.0;
        for (const Eigen::Vector3f& v : rock.vertices)
          extent = std::max(extent, (v.cast<double>() - centroid).norm());
        result.supports.push_back({centroid, extent});
        appendMesh(mesh, rock);
        break;
      }
      case SiteChangeType::kRemove:
      case SiteChangeType::kMove:
        result.supports = removeOrMove(mesh, change, where);
        break;
      case SiteChangeType::kGrow:
        result.displaced_volume_m3 = growPatch(mesh, change, where);
        result.supports.push_back({change.center, change.radius + std::abs(change.thickness)});
        break;
      case SiteChangeType::kAlbedo:
        changeAlbedo(mesh, change);
        result.supports.push_back({change.center, change.radius});
        break;
    }
    applied.push_back(result);
  }
  return applied;
}

}  // namespace auv::sim
