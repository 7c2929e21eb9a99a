#include "auv/recon/evaluate/change_truth.h"

#include <cmath>
#include <fstream>
#include <set>

#include <open3d/t/geometry/PointCloud.h>
#include <open3d/t/io/PointCloudIO.h>
#include <nlohmann/json.hpp>

#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";
constexpr const char* kFormat = "auv-sim-changes 1";

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

/// Reads the fields of changes.json, each error naming the file and the field.
class FieldReader {
 public:
  explicit FieldReader(const fs::path& file) : file_(file) {}

  [[noreturn]] void fail(const std::string& field, const std::string& why) const {
    throw StageError(kStage, file_.string() + ": " + field + ": " + why);
  }
  const json& at(const json& object, const std::string& path, const std::string& key) const {
    if (!object.is_object() || !object.contains(key)) fail(join(path, key), "missing");
    return object.at(key);
  }
  double number(const json& object, const std::string& path, const std::string& key) const {
    const json& value = at(object, path, key);
    if (!value.is_number() || !std::isfinite(value.get<double>())) {
      fail(join(path, key), "expected a number, got " + value.dump());
    }
    return value.get<double>();
  }
  std::string text(const json& object, const std::string& path, const std::string& key) const {
    const json& value = at(object, path, key);
    if (!value.is_string()) fail(join(path, key), "expected a string, got " + value.dump());
    return value.get<std::string>();
  }
  bool flag(const json& object, const std::string& path, const std::string& key) const {
    const json& value = at(object, path, key);
    if (!value.is_boolean()) fail(join(path, key), "expected true or false, got " + value.dump());
    return value.get<bool>();
  }
  Eigen::Vector3d point(const json& object, const std::string& path, const std::string& key) const {
    const json& value = at(object, path, key);
    if (!value.is_array() || value.size() != 3 || !value[0].is_number() || !value[1].is_number() ||
        !value[2].is_number()) {
      fail(join(path, key), "expected [x, y, z], got " + value.dump());
    }
    return {value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
  }

 private:
  fs::path file_;
};

TrueChangeRegion readRegion(const FieldReader& in, const json& j, const std::string& path) {
  static const std::set<std::string> kTypes = {"add", "remove", "move", "grow", "albedo"};
  TrueChangeRegion r;
  r.name = in.text(j, path, "name");
  r.change = in.text(j, path, "change");
  r.type = in.text(j, path, "type");
  if (!kTypes.count(r.type)) {
    in.fail(path + ".type", "expected add, remove, move, grow or albedo, got \"" + r.type + "\"");
  }
  r.geometric = in.flag(j, path, "geometric");
  r.centroid = in.point(j, path, "centroid");
  r.radius_m = in.number(j, path, "radius_m");
  r.area_m2 = in.number(j, path, "area_m2");
  r.mean_distance_m = in.number(j, path, "mean_distance_m");
  r.max_distance_m = in.number(j, path, "max_distance_m");
  r.volume_gained_m3 = in.number(j, path, "volume_gained_m3");
  r.volume_lost_m3 = in.number(j, path, "volume_lost_m3");
  const double points = in.number(j, path, "points");
  if (points < 0 || points != std::floor(points)) {
    in.fail(path + ".points", "expected a count, got " + in.at(j, path, "points").dump());
  }
  r.points = static_cast<size_t>(points);
  if (r.radius_m < 0) in.fail(path + ".radius_m", "must be >= 0");
  if (r.volume_gained_m3 < 0 || r.volume_lost_m3 < 0) {
    in.fail(path + ".volume_gained_m3/volume_lost_m3", "must be >= 0");
  }
  return r;
}

/// changes.ply: float x y z, float distance, int region (Open3D's tensor reader keeps every
/// vertex property by name).
void readPoints(const fs::path& file, ChangeTruth& truth) {
  if (!fs::exists(file)) {
    throw StageError(kStage, file.string() + ": not found (changes.json is there: was " +
                                 "`auv sim render` interrupted?)");
  }
  open3d::t::geometry::PointCloud cloud;
  if (!open3d::t::io::ReadPointCloud(file.string(), cloud,
                                     open3d::t::io::ReadPointCloudOption("ply"))) {
    throw StageError(kStage, file.string() + ": unreadable PLY");
  }
  const size_t n = cloud.HasPointPositions() ? cloud.GetPointPositions().GetLength() : 0;
  for (const char* property : {"distance", "region"}) {
    if (!cloud.HasPointAttr(property)) {
      throw StageError(kStage, file.string() + ": no vertex property \"" + property + "\"");
    }
  }
  namespace core = open3d::core;
  const core::Tensor xyz = cloud.GetPointPositions().To(core::Float64).Contiguous();
  const core::Tensor distance =
      cloud.GetPointAttr("distance").To(core::Float64).Reshape({-1}).Contiguous();
  const core::Tensor region =
      cloud.GetPointAttr("region").To(core::Int64).Reshape({-1}).Contiguous();
  if (static_cast<size_t>(distance.GetLength()) != n ||
      static_cast<size_t>(region.GetLength()) != n) {
    throw StageError(kStage, file.string() + ": distance and region must have one value a vertex");
  }
  const double* p = xyz.GetDataPtr<double>();
  const double* d = distance.GetDataPtr<double>();
  const int64_t* r = region.GetDataPtr<int64_t>();
  std::vector<size_t> counts(truth.regions.size(), 0);
  truth.points.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (r[i] < 0 || static_cast<size_t>(r[i]) >= truth.regions.size()) {
      throw StageError(kStage, file.string() + ": vertex " + std::to_string(i) + ": region " +
                                   std::to_string(r[i]) + " is not an index of the " +
                                   std::to_string(truth.regions.size()) +
                                   " regions of changes.json");
    }
    truth.points.emplace_back(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    truth.distances.push_back(d[i]);
    truth.region_of_point.push_back(static_cast<int>(r[i]));
    ++counts[r[i]];
  }
  for (size_t k = 0; k < counts.size(); ++k) {
    if (counts[k] != truth.regions[k].points) {
      throw StageError(kStage, file.string() + ": " + std::to_string(counts[k]) +
                                   " points of region " + std::to_string(k) + " (" +
                                   truth.regions[k].name + "), changes.json's regions[" +
                                   std::to_string(k) + "].points says " +
                                   std::to_string(truth.regions[k].points));
    }
  }
}

}  // namespace

fs::path changeTruthFile(const fs::path& ground_truth_run) {
  return ground_truth_run / "ground_truth" / "changes.json";
}

ChangeTruth readChangeTruth(const fs::path& json_file) {
  ChangeTruth truth;
  truth.json_file = json_file;
  truth.ply_file = json_file.parent_path() / "changes.ply";
  json document;
  try {
    std::ifstream in(json_file);
    if (!in) throw std::runtime_error("cannot be read");
    document = json::parse(in);
  } catch (const std::exception& e) {
    throw StageError(kStage, json_file.string() + ": " + e.what());
  }
  const FieldReader in(json_file);
  const std::string format = in.text(document, "", "format");
  if (format != kFormat) {
    in.fail("format", "expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");
  }
  truth.scenario = document.value("scenario", "");
  truth.min_distance_m = in.number(document, "", "min_distance_m");
  const json& regions = in.at(document, "", "regions");
  if (!regions.is_array()) in.fail("regions", "expected a list");
  std::set<std::string> names;
  for (size_t i = 0; i < regions.size(); ++i) {
    const std::string path = "regions[" + std::to_string(i) + "]";
    truth.regions.push_back(readRegion(in, regions[i], path));
    if (!names.insert(truth.regions.back().name).second) {
      in.fail(path + ".name", "\"" + truth.regions.back().name + "\" twice");
    }
  }
  // A control visit (`changes: []`) has no regions and so no points: every change is false.
  if (!truth.regions.empty()) readPoints(truth.ply_file, truth);
  return truth;
}

}  // namespace auv::recon::evaluate
