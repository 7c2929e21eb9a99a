// Benchmark (issue 21): `auv recon compare`'s M3C2 distances beside CloudCompare's (Debian,
// command-line mode) cloud-to-cloud distances (local least-squares plane model, the distance
// M3C2 builds on) and, when survey 1 has mesh/mesh.ply, its cloud-to-mesh distances, on the
// same aligned clouds, in the same run: median and 95th percentile of the absolute difference
// per core point, and both tools' times.
//
//   compare_vs_cloudcompare --survey-1 S1 --survey-2 S2 --work DIR
//                           [--out bench_results/compare_vs_cloudcompare.json]
//   compare_vs_cloudcompare --synthetic --work DIR ...   (two seabed surveys made in DIR:
//                           a 1 m block and 0.3 m of growth, the second frame off by 0.2 m)
//
// Survey 2's change/ is (re)written by the stage; CloudCompare works in DIR/cloudcompare.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/PointCloud.h>
#include <nlohmann/json.hpp>

#include "auv/recon/change/compare_stage.h"
#include "auv/recon/change/synthetic_site.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The synthetic site's two surveys (change/synthetic_site.h), the second changed, its frame
/// shifted, survey 1 with its mesh.
void makeSyntheticPair(const fs::path& s1, const fs::path& s2) {
  change::SyntheticSurvey first;
  first.with_mesh = true;
  change::writeSyntheticSurvey(s1, first);
  change::SyntheticSurvey second;
  second.changed = true;
  second.offset = Eigen::Vector3d(0.2, -0.1, 0.05);
  second.seed = 2;
  change::writeSyntheticSurvey(s2, second);
}

struct CorePoint {
  Eigen::Vector3d position;
  float distance;
};

/// change/changes.ply as compare_stage writes it: x y z nx ny nz + three float scalars.
std::vector<CorePoint> readChanges(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  size_t count = 0;
  while (std::getline(in, line) && line != "end_header") {
    if (line.rfind("element vertex ", 0) == 0) count = std::stoul(line.substr(15));
  }
  std::vector<CorePoint> points(count);
  for (CorePoint& p : points) {
    float v[9];
    in.read(reinterpret_cast<char*>(v), sizeof v);
    p.position = Eigen::Vector3d(v[0], v[1], v[2]);
    p.distance = v[6];
  }
  if (!in) throw std::runtime_error(file.string() + ": shorter than its header says");
  return points;
}

/// The points and last column of a CloudCompare ASCII export with a header line.
std::pair<std::vector<Eigen::Vector3d>, std::vector<double>> readAscii(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": CloudCompare wrote nothing");
  std::string line;
  std::getline(in, line);  // "//X Y Z <field>"
  std::vector<Eigen::Vector3d> points;
  std::vector<double> values;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    double x, y, z, value;
    if (fields >> x >> y >> z >> value) {
      points.emplace_back(x, y, z);
      values.push_back(value);
    }
  }
  return {points, values};
}

double runTimed(const std::string& command) {
  const auto start = Clock::now();
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return since(start);
}

/// |our distance| against the other tool's at the nearest of its points, per core point.
nlohmann::json differences(const std::vector<CorePoint>& cores,
                           const std::vector<Eigen::Vector3d>& points,
                           const std::vector<double>& values, bool signed_values,
                           double max_gap_m) {
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = points[i];
  const open3d::geometry::KDTreeFlann tree(matrix);
  std::vector<double> diffs;
  std::vector<int> index;
  std::vector<double> distance2;
  for (const CorePoint& core : cores) {
    if (!std::isfinite(core.distance)) continue;
    if (tree.SearchKNN(core.position, 1, index, distance2) < 1 ||
        std::sqrt(distance2[0]) > max_gap_m) {
      continue;
    }
    const double theirs = values[static_cast<size_t>(index[0])];
    const double ours = signed_values ? core.distance : std::abs(core.distance);
    diffs.push_back(std::abs(ours - (signed_values ? theirs : std::abs(theirs))));
  }
  std::sort(diffs.begin(), diffs.end());
  const auto quantile = [&](double q) {
    return diffs.empty() ? 0.0 : diffs[static_cast<size_t>(q * (diffs.size() - 1))];
  };
  return {{"core_points", diffs.size()},
          {"median_abs_difference_m", quantile(0.5)},
          {"p95_abs_difference_m", quantile(0.95)}};
}

}  // namespace

int main(int argc, char** argv) {
  fs::path s1, s2, work, out;
  bool synthetic = false;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "--synthetic") {
      synthetic = true;
    } else if (i + 1 < argc && key == "--survey-1") {
      s1 = argv[++i];
    } else if (i + 1 < argc && key == "--survey-2") {
      s2 = argv[++i];
    } else if (i + 1 < argc && key == "--work") {
      work = argv[++i];
    } else if (i + 1 < argc && key == "--out") {
      out = argv[++i];
    } else {
      std::cerr << "compare_vs_cloudcompare: unknown or incomplete option " << key << "\n";
      return 2;
    }
  }
  if (work.empty() || (!synthetic && (s1.empty() || s2.empty()))) {
    std::cerr << "usage: compare_vs_cloudcompare (--survey-1 S1 --survey-2 S2 | --synthetic) "
                 "--work DIR [--out FILE.json]\n";
    return 2;
  }
  try {
    fs::create_directories(work);
    if (synthetic) {
      s1 = work / "synthetic-1";
      s2 = work / "synthetic-2";
      makeSyntheticPair(s1, s2);
    }
    change::CompareOptions options;
    options.later = s2.string();
    auto start = Clock::now();
    const nlohmann::json report = change::runCompare(Survey(s1), options);
    const double ours_s = since(start);

    // The same aligned clouds for CloudCompare: survey 1 as is, survey 2 moved onto it.
    const fs::path cc = work / "cloudcompare";
    fs::remove_all(cc);
    fs::create_directories(cc);
    const auto first = scene::readCloud(Survey(s1).dense() / "fused.ply", "bench", "dense");
    auto second = scene::readCloud(Survey(s2).dense() / "fused.ply", "bench", "dense");
    Eigen::Matrix4d transform;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c)
        transform(r, c) = report["registration"]["transform_2_to_1"][r][c];
    }
    second.Transform(transform);
    scene::PlyData ply1, ply2;
    ply1.positions = first.points_;
    ply2.positions = second.points_;
    scene::writePly(cc / "survey1.ply", ply1);
    scene::writePly(cc / "survey2.ply", ply2);
    const std::string prefix = "cd '" + cc.string() +
                               "' && QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP "
                               "-AUTO_SAVE OFF -C_EXPORT_FMT ASC -ADD_HEADER ";
    const double radius = 0.5 * options.m3c2.normal_scale_m;
    std::ostringstream c2c;
    c2c << prefix << "-O survey2.ply -O survey1.ply -C2C_DIST -MODEL LS SPHERE " << radius
        << " -POP_CLOUDS -SAVE_CLOUDS FILE c2c.asc > c2c.log 2>&1";
    const double c2c_s = runTimed(c2c.str());
    const std::vector<CorePoint> cores = readChanges(Survey(s2).root() / "change" / "changes.ply");
    const auto [c2c_points, c2c_values] = readAscii(cc / "c2c.asc");
    nlohmann::json result = {
        {"survey_1", s1.string()},
        {"survey_2", s2.string()},
        {"ours", {{"seconds", ours_s}, {"report", report}}},
        {"c2c_least_squares_plane",
         differences(cores, c2c_points, c2c_values, false, options.core_spacing_m)}};
    result["c2c_least_squares_plane"]["seconds"] = c2c_s;
    result["c2c_least_squares_plane"]["radius_m"] = radius;
    const fs::path mesh = Survey(s1).mesh() / "mesh.ply";
    if (fs::exists(mesh)) {
      fs::copy_file(mesh, cc / "mesh1.ply", fs::copy_options::overwrite_existing);
      const double c2m_s =
          runTimed(prefix +
                   "-O survey2.ply -O mesh1.ply -C2M_DIST -POP_MESHES -SAVE_CLOUDS FILE c2m.asc "
                   "> c2m.log 2>&1");
      const auto [c2m_points, c2m_values] = readAscii(cc / "c2m.asc");
      result["c2m_signed"] =
          differences(cores, c2m_points, c2m_values, true, options.core_spacing_m);
      result["c2m_signed"]["seconds"] = c2m_s;
    }
    const auto& lsq = result["c2c_least_squares_plane"];
    std::cout << "ours (coregistration + M3C2 + regions): " << ours_s << " s, "
              << report["core_points_measured"] << " core points measured\n"
              << "CloudCompare C2C (least-squares plane, r " << radius << " m): " << c2c_s
              << " s; | |M3C2| - C2C |: median " << lsq["median_abs_difference_m"] << " m, p95 "
              << lsq["p95_abs_difference_m"] << " m over " << lsq["core_points"]
              << " core points\n";
    if (result.contains("c2m_signed")) {
      const auto& c2m = result["c2m_signed"];
      std::cout << "CloudCompare C2M (signed, survey 1's mesh): " << c2m["seconds"]
                << " s; | M3C2 - C2M |: median " << c2m["median_abs_difference_m"] << " m, p95 "
                << c2m["p95_abs_difference_m"] << " m\n";
    }
    if (!out.empty()) {
      if (out.has_parent_path()) fs::create_directories(out.parent_path());
      std::ofstream(out) << result.dump(2) << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "compare_vs_cloudcompare: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
