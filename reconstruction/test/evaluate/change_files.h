#pragma once
// Writers of the two sides the change evaluation reads, for the tests: the simulator's change
// truth (ground_truth/changes.json + changes.ply, exactly as components/simulator's
// change_truth.cc writes them) and `auv recon compare`'s output (change/changes.ply +
// report.json, as change/compare_stage.cc writes them).

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "auv/recon/scene/ply.h"

namespace auv::recon::evaluate::testing {

/// One true region and its points.
struct TruthRegionFixture {
  nlohmann::json region;  ///< the changes.json entry ("points" is filled in)
  std::vector<Eigen::Vector3d> points;
  double distance = 0;  ///< of every point
};

/// A truth region whose points cover the rectangle [x0, x1] x [y0, y1] at depth z every
/// `step` m, each with `distance`; the entry's area, distances and volumes follow from them.
inline TruthRegionFixture rectangleRegion(const std::string& name, const std::string& type,
                                          double x0, double x1, double y0, double y1, double z,
                                          double distance, double step = 0.05) {
  TruthRegionFixture r;
  r.distance = distance;
  for (double x = x0; x <= x1 + 1e-9; x += step) {
    for (double y = y0; y <= y1 + 1e-9; y += step) r.points.emplace_back(x, y, z);
  }
  const double area = (x1 - x0) * (y1 - y0);
  const double volume = area * std::abs(distance);
  const Eigen::Vector3d c(0.5 * (x0 + x1), 0.5 * (y0 + y1), z);
  r.region = {{"name", name},
              {"change", name},
              {"type", type},
              {"geometric", type != "albedo"},
              {"centroid", {c.x(), c.y(), c.z()}},
              {"radius_m", 0.5 * std::hypot(x1 - x0, y1 - y0)},
              {"area_m2", area},
              {"mean_distance_m", distance},
              {"max_distance_m", distance},
              {"volume_gained_m3", distance > 0 ? volume : 0.0},
              {"volume_lost_m3", distance < 0 ? volume : 0.0}};
  return r;
}

/// A block standing on the seabed at depth `z_base` (NED, z down) up to `z_top`, over the
/// rectangle [x0, x1] x [y0, y1]: its top and its four sides every `step` m, as the simulator
/// samples an added block's surface (the sides reach down to the seabed), each point with the
/// block's height as distance.
inline TruthRegionFixture boxRegion(const std::string& name, const std::string& type, double x0,
                                    double x1, double y0, double y1, double z_top, double z_base,
                                    double step = 0.05) {
  const double height = z_base - z_top;
  TruthRegionFixture r = rectangleRegion(name, type, x0, x1, y0, y1, z_top, height, step);
  for (double z = z_top + step; z <= z_base + 1e-9; z += step) {
    for (double x = x0; x <= x1 + 1e-9; x += step) {
      r.points.emplace_back(x, y0, z);
      r.points.emplace_back(x, y1, z);
    }
    for (double y = y0 + step; y < y1 - 1e-9; y += step) {
      r.points.emplace_back(x0, y, z);
      r.points.emplace_back(x1, y, z);
    }
  }
  r.region["area_m2"] = (x1 - x0) * (y1 - y0) + 2 * ((x1 - x0) + (y1 - y0)) * height;
  return r;
}

/// <folder>/changes.json and changes.ply of `regions`: binary little-endian PLY, float x y z,
/// float distance, int region.
inline void writeChangeTruthFiles(const std::filesystem::path& folder,
                                  std::vector<TruthRegionFixture> regions) {
  std::filesystem::create_directories(folder);
  nlohmann::json list = nlohmann::json::array();
  size_t total = 0;
  for (TruthRegionFixture& r : regions) {
    r.region["points"] = r.points.size();
    list.push_back(r.region);
    total += r.points.size();
  }
  std::ofstream(folder / "changes.json") << nlohmann::json({{"format", "auv-sim-changes 1"},
                                                            {"scenario", "synthetic.yaml"},
                                                            {"frame", "world NED, m"},
                                                            {"spacing_m", 0.05},
                                                            {"min_distance_m", 0.01},
                                                            {"regions", list}})
                                                .dump(2);
  std::ofstream out(folder / "changes.ply", std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << total << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property float distance\nproperty int region\nend_header\n";
  for (size_t k = 0; k < regions.size(); ++k) {
    for (const Eigen::Vector3d& p : regions[k].points) {
      const float values[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                               static_cast<float>(p.z()), static_cast<float>(regions[k].distance)};
      const int32_t region = static_cast<int32_t>(k);
      out.write(reinterpret_cast<const char*>(values), sizeof(values));
      out.write(reinterpret_cast<const char*>(&region), sizeof(region));
    }
  }
}

/// compare's core points: positions, normals, distances (NaN: not measured), significance;
/// optionally the appearance change (empty: written as an older compare wrote them, without).
struct ComparisonFixture {
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<double> distances;
  std::vector<char> significant;
  std::vector<double> delta_e;  ///< NaN: colour not compared
  std::vector<char> appearance_significant;

  void add(const Eigen::Vector3d& p, double distance, bool significant_change,
           const Eigen::Vector3d& normal = Eigen::Vector3d(0, 0, -1)) {
    points.push_back(p);
    normals.push_back(normal);
    distances.push_back(distance);
    significant.push_back(significant_change ? 1 : 0);
  }
};

/// <survey>/change/changes.ply and report.json as compare writes them (an older compare: without
/// the appearance fields when `c` has none).
inline void writeComparison(const std::filesystem::path& survey, const ComparisonFixture& c,
                            const nlohmann::json& report) {
  scene::PlyData ply;
  ply.positions = c.points;
  ply.normals = c.normals;
  std::vector<float> distance, lod, flag;
  for (size_t i = 0; i < c.points.size(); ++i) {
    distance.push_back(static_cast<float>(c.distances[i]));
    lod.push_back(0.05f);
    flag.push_back(c.significant[i] ? 1.0f : 0.0f);
  }
  ply.scalars = {{"scalar_distance", distance},
                 {"scalar_level_of_detection", lod},
                 {"scalar_significant", flag}};
  if (!c.appearance_significant.empty()) {
    std::vector<float> delta_e, colour_flag;
    for (size_t i = 0; i < c.points.size(); ++i) {
      delta_e.push_back(static_cast<float>(c.delta_e[i]));
      colour_flag.push_back(c.appearance_significant[i] ? 1.0f : 0.0f);
    }
    ply.scalars.emplace_back("scalar_delta_e", delta_e);
    ply.scalars.emplace_back("scalar_appearance_significant", colour_flag);
  }
  std::filesystem::create_directories(survey / "change");
  scene::writePly(survey / "change" / "changes.ply", ply);
  std::ofstream(survey / "change" / "report.json") << report.dump(2);
}

}  // namespace auv::recon::evaluate::testing
