#include "auv/foxglove_bridge/scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace auv::foxglove_bridge {
namespace {

using nlohmann::json;

json time(int64_t ns) {
  const int64_t sec = ns >= 0 ? ns / 1000000000 : (ns - 999999999) / 1000000000;
  return {{"sec", sec}, {"nsec", ns - sec * 1000000000}};
}
json time(const msg::Time& t) { return {{"sec", t.sec()}, {"nsec", t.nanosec()}}; }
// Millimetres are plenty for a viewer and make the JSON of a large tree or map 2-3x shorter
// than 17 significant digits.
double mm(double v) { return std::round(v * 1000.0) / 1000.0; }
json vec(double x, double y, double z) { return {{"x", mm(x)}, {"y", mm(y)}, {"z", mm(z)}}; }
json point(const msg::Point& p) { return vec(p.x(), p.y(), p.z()); }
json colour(double r, double g, double b, double a) {
  return {{"r", r}, {"g", g}, {"b", b}, {"a", a}};
}
json identityPose() {
  return {{"position", vec(0, 0, 0)}, {"orientation", {{"x", 0}, {"y", 0}, {"z", 0}, {"w", 1}}}};
}

// A SceneEntity with every primitive list present (Foxglove's schema has them all).
json entity(const std::string& id, const std::string& frame, const json& stamp) {
  return {{"timestamp", stamp},         {"frame_id", frame},      {"id", id},
          {"lifetime", time(0)},        {"frame_locked", false},  {"metadata", json::array()},
          {"arrows", json::array()},    {"cubes", json::array()}, {"spheres", json::array()},
          {"cylinders", json::array()}, {"lines", json::array()}, {"triangles", json::array()},
          {"texts", json::array()},     {"models", json::array()}};
}

json sceneUpdate(json entities) {
  return {{"deletions", json::array()}, {"entities", std::move(entities)}};
}

// LinePrimitive: type 0 line strip, 1 line loop, 2 line list.
json line(int type, json points, const json& color, double thickness) {
  return {{"type", type},
          {"pose", identityPose()},
          {"thickness", thickness},
          {"scale_invariant", false},
          {"points", std::move(points)},
          {"color", color},
          {"colors", json::array()},
          {"indices", json::array()}};
}

json cube(double x, double y, double z, double size, const json& color) {
  json pose = identityPose();
  pose["position"] = vec(x, y, z);
  return {{"pose", pose}, {"size", vec(size, size, size)}, {"color", color}};
}

// Depth (z, NED) to a colour ramp, so the map's relief reads at a glance.
json depthColour(double z, double z_min, double z_max) {
  const double t = z_max > z_min ? std::clamp((z - z_min) / (z_max - z_min), 0.0, 1.0) : 0.5;
  return colour(0.9 - 0.6 * t, 0.6 + 0.2 * t * (1 - t), 0.3 + 0.6 * t, 1.0);
}

json objectSchema(const std::string& title, json properties) {
  return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
          {"title", title},
          {"type", "object"},
          {"properties", std::move(properties)}};
}

}  // namespace

const std::string& jsonSchema(const std::string& schema_name) {
  // Foxglove picks the panel by schema name; the schema documents the fields we fill.
  const json time_s = {
      {"type", "object"},
      {"properties", {{"sec", {{"type", "integer"}}}, {"nsec", {{"type", "integer"}}}}}};
  const json vector3 = {
      {"type", "object"},
      {"properties",
       {{"x", {{"type", "number"}}}, {"y", {{"type", "number"}}}, {"z", {{"type", "number"}}}}}};
  const json quaternion = {{"type", "object"},
                           {"properties",
                            {{"x", {{"type", "number"}}},
                             {"y", {{"type", "number"}}},
                             {"z", {{"type", "number"}}},
                             {"w", {{"type", "number"}}}}}};
  const json pose = {{"type", "object"},
                     {"properties", {{"position", vector3}, {"orientation", quaternion}}}};
  const json color = {{"type", "object"},
                      {"properties",
                       {{"r", {{"type", "number"}}},
                        {"g", {{"type", "number"}}},
                        {"b", {{"type", "number"}}},
                        {"a", {{"type", "number"}}}}}};
  const json primitives = {{"type", "array"}, {"items", {{"type", "object"}}}};
  static const std::string scene =
      objectSchema(
          kSceneUpdate,
          {{"deletions", {{"type", "array"}, {"items", {{"type", "object"}}}}},
           {"entities",
            {{"type", "array"},
             {"items",
              {{"type", "object"},
               {"properties",
                {{"timestamp", time_s},
                 {"frame_id", {{"type", "string"}}},
                 {"id", {{"type", "string"}}},
                 {"lifetime", time_s},
                 {"frame_locked", {{"type", "boolean"}}},
                 {"metadata", primitives},
                 {"arrows", primitives},
                 {"cubes",
                  {{"type", "array"},
                   {"items",
                    {{"type", "object"},
                     {"properties", {{"pose", pose}, {"size", vector3}, {"color", color}}}}}}},
                 {"spheres", primitives},
                 {"cylinders", primitives},
                 {"lines", primitives},
                 {"triangles", primitives},
                 {"texts", primitives},
                 {"models", primitives}}}}}}}})
          .dump();
  static const std::string transform =
      objectSchema(kFrameTransform, {{"timestamp", time_s},
                                     {"parent_frame_id", {{"type", "string"}}},
                                     {"child_frame_id", {{"type", "string"}}},
                                     {"translation", vector3},
                                     {"rotation", quaternion}})
          .dump();
  static const std::string image =
      objectSchema(kCompressedImage, {{"timestamp", time_s},
                                      {"frame_id", {{"type", "string"}}},
                                      {"data", {{"type", "string"}, {"contentEncoding", "base64"}}},
                                      {"format", {{"type", "string"}}}})
          .dump();
  if (schema_name == kSceneUpdate) return scene;
  if (schema_name == kFrameTransform) return transform;
  if (schema_name == kCompressedImage) return image;
  throw std::invalid_argument("no JSON schema for '" + schema_name + "'");
}

json mapScene(const octomap::OcTree& tree, const MapStyle& style, int64_t stamp_ns,
              bool* truncated) {
  const json stamp = time(stamp_ns);
  json map = entity("map", "world", stamp);
  json& cubes = map["cubes"];
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  bool cut = false;
  const json faint_free = colour(0.3, 0.8, 0.3, 0.08);
  // Occupied first: a cut keeps the surfaces.
  for (int pass = 0; pass < 2 && !cut; ++pass) {
    if (pass == 1 && !style.show_free) break;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
      const bool occupied = tree.isNodeOccupied(*it);
      if (occupied != (pass == 0)) continue;
      if (cubes.size() >= style.max_cubes) {
        cut = true;
        break;
      }
      cubes.push_back(cube(it.getX(), it.getY(), it.getZ(), it.getSize(),
                           occupied ? depthColour(it.getZ(), z0, z1) : faint_free));
    }
  }
  const double r = tree.getResolution();
  const double cells =
      std::ceil((x1 - x0) / r) * std::ceil((y1 - y0) / r) * std::ceil((z1 - z0) / r);
  // Each cell of the extent costs a lookup: a large sparse extent is cut rather than walked.
  if (style.show_unknown && !cut && tree.size() > 0 && cells > 10.0 * style.max_cubes) cut = true;
  if (style.show_unknown && !cut && tree.size() > 0) {
    const json faint_unknown = colour(0.5, 0.5, 0.5, 0.05);
    for (double x = x0 + r / 2; x < x1 && !cut; x += r)
      for (double y = y0 + r / 2; y < y1 && !cut; y += r)
        for (double z = z0 + r / 2; z < z1; z += r) {
          if (tree.search(x, y, z) != nullptr) continue;
          if (cubes.size() >= style.max_cubes) {
            cut = true;
            break;
          }
          cubes.push_back(cube(x, y, z, r, faint_unknown));
        }
  }
  map["metadata"].push_back({{"key", "truncated"}, {"value", cut ? "true" : "false"}});
  if (truncated) *truncated = cut;
  return sceneUpdate(json::array({map}));
}

json treeScene(const msg::PlannerTree& tree) {
  json e = entity("tree", "world", time(tree.header().stamp()));
  // Each node once, edges as index pairs (LinePrimitive.indices): half the JSON of a point pair
  // per edge.
  json points = json::array();
  json indices = json::array();
  const auto& nodes = tree.nodes();
  const auto& parents = tree.parents();
  for (const auto& node : nodes) points.push_back(point(node));
  for (size_t i = 0; i < nodes.size() && i < parents.size(); ++i) {
    const int32_t parent = parents[i];
    if (parent < 0 || static_cast<size_t>(parent) >= nodes.size()) continue;
    indices.push_back(parent);
    indices.push_back(i);
  }
  json edges = line(2, std::move(points), colour(0.6, 0.6, 0.6, 0.6), 0.02);
  edges["indices"] = std::move(indices);
  e["lines"].push_back(std::move(edges));
  e["metadata"].push_back({{"key", "query_id"}, {"value", std::to_string(tree.query_id())}});
  return sceneUpdate(json::array({e}));
}

json pathScene(const msg::Path& path) {
  json e = entity("path", "world", time(path.header().stamp()));
  json points = json::array();
  for (const auto& pose : path.poses()) points.push_back(point(pose.position()));
  e["lines"].push_back(line(0, std::move(points), colour(1.0, 0.6, 0.0, 1.0), 0.08));
  e["metadata"].push_back({{"key", "query_id"}, {"value", std::to_string(path.query_id())}});
  return sceneUpdate(json::array({e}));
}

bool Trajectory::add(double x, double y, double z) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return false;
  if (!points_.empty()) {
    const auto& last = points_.back();
    const double dx = x - last.x(), dy = y - last.y(), dz = z - last.z();
    if (dx * dx + dy * dy + dz * dz < min_step_ * min_step_) return false;
  }
  msg::Point p;
  p.x(x);
  p.y(y);
  p.z(z);
  points_.push_back(p);
  while (points_.size() > max_points_) points_.pop_front();
  return true;
}

json vehicleScene(const Trajectory& estimated, const Trajectory& truth, int64_t stamp_ns,
                  double length, double width) {
  const json stamp = time(stamp_ns);
  json vehicle = entity("vehicle", "vehicle", stamp);
  vehicle["frame_locked"] = true;
  json box = cube(0, 0, 0, 1, colour(1.0, 0.8, 0.0, 1.0));
  box["size"] = vec(length, width, width);  // body x forward
  vehicle["cubes"].push_back(box);
  json entities = json::array({vehicle});
  const auto strip = [&](const char* id, const Trajectory& t, const json& c) {
    if (t.points().empty()) return;
    json e = entity(id, "world", stamp);
    json points = json::array();
    for (const auto& p : t.points()) points.push_back(point(p));
    e["lines"].push_back(line(0, std::move(points), c, 0.05));
    entities.push_back(std::move(e));
  };
  strip("trajectory_estimated", estimated, colour(0.2, 0.8, 0.4, 1.0));
  strip("trajectory_true", truth, colour(1.0, 1.0, 1.0, 1.0));
  return sceneUpdate(std::move(entities));
}

json vehicleTransform(const msg::Odometry& odometry) {
  const auto& pose = odometry.pose().pose();
  const auto& q = pose.orientation();
  return {{"timestamp", time(odometry.header().stamp())},
          {"parent_frame_id", "world"},
          {"child_frame_id", "vehicle"},
          {"translation", point(pose.position())},
          {"rotation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}

json displayFrameTransform(int64_t stamp_ns) {
  // Half a turn about (1, 1, 0) / sqrt(2): x <-> y, z -> -z (NED <-> ENU).
  const double h = std::sqrt(0.5);
  return {{"timestamp", time(stamp_ns)},
          {"parent_frame_id", kDisplayFrame},
          {"child_frame_id", "world"},
          {"translation", vec(0, 0, 0)},
          {"rotation", {{"x", h}, {"y", h}, {"z", 0.0}, {"w", 0.0}}}};
}

json compressedImage(const msg::CompressedImage& image) {
  return {{"timestamp", time(image.header().stamp())},
          {"frame_id", image.header().frame_id()},
          {"data", base64(image.data().data(), image.data().size())},
          {"format", image.format()}};
}

std::string cameraChannel(const std::string& topic) {
  std::string name = topic;
  while (!name.empty() && name.front() == '/') name.erase(0, 1);
  if (name.rfind("camera/", 0) == 0) name.erase(0, 7);
  const std::string suffix = "/compressed";
  if (name.size() > suffix.size() &&
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
    name.erase(name.size() - suffix.size());
  return kCameraChannelPrefix + name;
}

std::string base64(const uint8_t* data, size_t size) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const uint32_t v = data[i] << 16 | data[i + 1] << 8 | data[i + 2];
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < size) {
    const uint32_t v = data[i] << 16 | (i + 1 < size ? data[i + 1] << 8 : 0);
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace auv::foxglove_bridge
