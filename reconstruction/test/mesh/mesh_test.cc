// Poisson surface + trimming (docs/paper.md §3.6) on synthetic clouds with known geometry: an open
// terrain patch, whose watertight Poisson closure (a false surface under and around the patch)
// must be trimmed away while the observed surface stays.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <random>

#include <open3d/io/PointCloudIO.h>
#include <nlohmann/json.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/mesh/surface.h"
#include "auv/recon/scene/mesh_io.h"

namespace fs = std::filesystem;
namespace o3d = open3d::geometry;
using namespace auv::recon;
using namespace auv::recon::mesh;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_mesh_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Terrain z = f(x, y) over [-1, 1]^2 (metres): gentle hills, 0.15 m high.
double height(double x, double y) { return 0.1 * std::sin(2.0 * x) * std::cos(1.5 * y) + 0.05 * x; }
Eigen::Vector3d normalAt(double x, double y) {
  const double dx = 0.2 * std::cos(2.0 * x) * std::cos(1.5 * y) + 0.05;
  const double dy = -0.15 * std::sin(2.0 * x) * std::sin(1.5 * y);
  return Eigen::Vector3d(-dx, -dy, 1.0).normalized();
}

/// Oriented, coloured samples of the terrain with a little noise (1 mm).
/// `hole_radius` > 0: no samples within that distance of (0, 0), an unobserved area.
o3d::PointCloud terrainCloud(size_t n, double hole_radius = 0, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.001);
  o3d::PointCloud cloud;
  for (size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    if (x * x + y * y < hole_radius * hole_radius) continue;
    cloud.points_.emplace_back(x, y, height(x, y) + noise(rng));
    cloud.normals_.push_back(normalAt(x, y));
    cloud.colors_.emplace_back(0.5 + 0.4 * x, 0.5, 0.5 + 0.4 * y);
  }
  return cloud;
}

/// Area of the triangles whose centroid lies farther than `tolerance` from the true terrain
/// (off the patch footprint, or off its height): the false surface.
struct AreaSplit {
  double true_area = 0, false_area = 0;
};
AreaSplit splitArea(const o3d::TriangleMesh& mesh, double tolerance) {
  AreaSplit split;
  for (const auto& t : mesh.triangles_) {
    const Eigen::Vector3d& a = mesh.vertices_[t(0)];
    const Eigen::Vector3d& b = mesh.vertices_[t(1)];
    const Eigen::Vector3d& c = mesh.vertices_[t(2)];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d m = (a + b + c) / 3.0;
    const bool on_footprint =
        std::abs(m.x()) <= 1.0 + tolerance && std::abs(m.y()) <= 1.0 + tolerance;
    const bool on_surface = on_footprint && std::abs(m.z() - height(m.x(), m.y())) <= tolerance;
    (on_surface ? split.true_area : split.false_area) += area;
  }
  return split;
}

SurfaceOptions fastOptions() {
  SurfaceOptions options;
  options.poisson_depth = 7;  // 2.2 m / 128 = 17 mm cells: fast, enough for a 2 m patch
  options.threads = 1;
  return options;
}

}  // namespace

TEST(Surface, TrimmingRemovesThePoissonClosureOfAnOpenTerrain) {
  const o3d::PointCloud cloud = terrainCloud(20000);
  // A Poisson cube twice the cloud's extent leaves the indicator function room to close the
  // open patch with a false surface reaching far beyond the footprint.
  SurfaceOptions options = fastOptions();
  options.poisson_depth = 8;  // 4.4 m / 256 = 17 mm cells
  options.poisson_scale = 2.0;
  const SurfaceResult result = reconstructSurface(cloud, options);
  const double tolerance = 0.03;  // m: ~2 finest cells
  const AreaSplit before = splitArea(*result.untrimmed, tolerance);
  const AreaSplit after = splitArea(*result.trimmed, tolerance);
  const double true_area = 4.0;  // footprint of the terrain (its slope adds ~1 %)
  std::cout << "area on the terrain / false: before " << before.true_area << " / "
            << before.false_area << " m2, after " << after.true_area << " / " << after.false_area
            << " m2; removed long-edge " << result.stats.removed_long_edges << ", low-density "
            << result.stats.removed_low_density << ", components "
            << result.stats.removed_components << std::endl;
  // The planted false surface: larger than the true one.
  EXPECT_GT(before.false_area, true_area);
  // Trimming removes nearly all of it and keeps the observed surface.
  EXPECT_LT(after.false_area, 0.03 * true_area);
  EXPECT_GT(after.true_area, 0.90 * true_area);
  // The slope adds ~1 % and the tolerance band around the footprint ~6 %.
  EXPECT_LE(after.true_area, 1.08 * true_area);
  EXPECT_EQ(result.stats.triangles, result.trimmed->triangles_.size());
  EXPECT_LT(result.stats.triangles, result.stats.poisson_triangles);
  // The winding follows the cloud's normals (up, towards the cameras): the texturing takes
  // its face normals from it.
  size_t up = 0, down = 0;
  for (const auto& t : result.trimmed->triangles_) {
    const auto& mv = result.trimmed->vertices_;
    const Eigen::Vector3d n = (mv[t(1)] - mv[t(0)]).cross(mv[t(2)] - mv[t(0)]);
    (n.z() > 0 ? up : down)++;
  }
  EXPECT_LT(down * 1000, up) << down << " of " << up + down << " triangles wound downwards";
  // Vertex colours come from the cloud (x-dependent red).
  ASSERT_TRUE(result.trimmed->HasVertexColors());
  const auto& v = result.trimmed->vertices_;
  const auto& c = result.trimmed->vertex_colors_;
  for (size_t i = 0; i < v.size(); i += 97) {
    EXPECT_NEAR(c[i].x(), 0.5 + 0.4 * std::clamp(v[i].x(), -1.0, 1.0), 0.02) << "vertex " << i;
  }
}

TEST(Surface, TrimmingOpensAnUnobservedHole) {
  // No samples within 0.4 m of the centre (seen by no camera): Poisson fills it with a smooth
  // guess; the trimmed mesh must not claim the unobserved middle of it.
  const o3d::PointCloud cloud = terrainCloud(20000, 0.4);
  const SurfaceResult result = reconstructSurface(cloud, fastOptions());
  auto areaWithin = [](const o3d::TriangleMesh& mesh, double r_min, double r_max) {
    double area = 0;
    for (const auto& t : mesh.triangles_) {
      const Eigen::Vector3d& a = mesh.vertices_[t(0)];
      const Eigen::Vector3d& b = mesh.vertices_[t(1)];
      const Eigen::Vector3d& c = mesh.vertices_[t(2)];
      const Eigen::Vector3d m = (a + b + c) / 3.0;
      const double r = m.head<2>().norm();
      if (r >= r_min && r < r_max && std::abs(m.x()) < 1 && std::abs(m.y()) < 1) {
        area += 0.5 * (b - a).cross(c - a).norm();
      }
    }
    return area;
  };
  const double unobserved_before = areaWithin(*result.untrimmed, 0, 0.3);
  const double unobserved_after = areaWithin(*result.trimmed, 0, 0.3);
  const double observed_before = areaWithin(*result.untrimmed, 0.5, 10);
  const double observed_after = areaWithin(*result.trimmed, 0.5, 10);
  std::cout << "unobserved (r < 0.3 m) " << unobserved_before << " -> " << unobserved_after
            << " m2, observed (r > 0.5 m) " << observed_before << " -> " << observed_after << " m2"
            << std::endl;
  EXPECT_GT(unobserved_before, 0.8 * M_PI * 0.3 * 0.3);  // Poisson closed the hole
  EXPECT_LT(unobserved_after, 0.1 * M_PI * 0.3 * 0.3);
  EXPECT_GT(observed_after, 0.95 * observed_before);
}

TEST(Surface, EachTrimmingCriterionAloneRemovesPartOfTheClosure) {
  const o3d::PointCloud cloud = terrainCloud(20000);
  SurfaceOptions edges_only = fastOptions();
  edges_only.poisson_scale = 2.0;
  edges_only.density_quantile = 0;
  edges_only.density_drop_levels = 0;
  edges_only.min_component_fraction = 0;
  SurfaceOptions density_only = edges_only;
  density_only.density_quantile = 0.1;
  density_only.density_drop_levels = 1.5;
  density_only.max_edge_factor = 0;
  const SurfaceResult by_edges = reconstructSurface(cloud, edges_only);
  const SurfaceResult by_density = reconstructSurface(cloud, density_only);
  const double untrimmed_false = splitArea(*by_edges.untrimmed, 0.03).false_area;
  EXPECT_GT(by_edges.stats.removed_long_edges, 0u);
  EXPECT_EQ(by_edges.stats.removed_low_density, 0u);
  EXPECT_LT(splitArea(*by_edges.trimmed, 0.03).false_area, 0.7 * untrimmed_false);
  EXPECT_GT(by_density.stats.removed_low_density, 0u);
  EXPECT_EQ(by_density.stats.removed_long_edges, 0u);
  EXPECT_LT(splitArea(*by_density.trimmed, 0.03).false_area, 0.7 * untrimmed_false);
}

TEST(Surface, TooFewPointsOrNoNormalsStopWithTheCause) {
  o3d::PointCloud empty;
  try {
    reconstructSurface(empty, fastOptions());
    FAIL() << "an empty cloud was accepted";
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "mesh");
    EXPECT_NE(std::string(e.what()).find("0 points"), std::string::npos) << e.what();
  }
  o3d::PointCloud tiny = terrainCloud(20);
  EXPECT_THROW(reconstructSurface(tiny, fastOptions()), StageError);
  o3d::PointCloud no_normals = terrainCloud(500);
  no_normals.normals_.clear();
  try {
    reconstructSurface(no_normals, fastOptions());
    FAIL() << "a cloud without normals was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("normals"), std::string::npos) << e.what();
  }
}

TEST(Surface, OptionsRejectBadValuesNamingTheField) {
  SurfaceOptions options;
  options.poisson_depth = 2;
  try {
    options.check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("poisson_depth = 2"), std::string::npos) << e.what();
  }
  options = SurfaceOptions();
  options.density_quantile = 1.5;
  EXPECT_THROW(options.check(), OptionError);
  options = SurfaceOptions();
  options.max_edge_factor = 0.5;
  EXPECT_THROW(options.check(), OptionError);
  EXPECT_NO_THROW(SurfaceOptions().check());
}

TEST(MeshStage, WritesTheMeshAndReportAndKeepsEarlierOutputsOnFailure) {
  TempDir dir;
  const Survey survey(dir.path / "survey");
  MeshStageOptions options;
  options.surface = fastOptions();

  // No dense cloud yet: the error names the missing file and the stage that makes it.
  try {
    runMeshStage(survey, options);
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("fused.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("auv recon dense"), std::string::npos) << e.what();
  }

  fs::create_directories(survey.dense());
  ASSERT_TRUE(
      open3d::io::WritePointCloud((survey.dense() / "fused.ply").string(), terrainCloud(15000)));
  const MeshStageResult summary = runMeshStage(survey, options);
  const o3d::TriangleMesh written = scene::readMesh(survey.mesh() / "mesh.ply", "test");
  EXPECT_EQ(written.triangles_.size(), summary.stats.triangles);
  EXPECT_TRUE(written.HasVertexColors());
  EXPECT_TRUE(fs::exists(survey.mesh() / "mesh_untrimmed.ply"));
  EXPECT_NEAR(summary.area, 4.0, 0.4);
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["mesh"]["triangles"].get<size_t>(), summary.stats.triangles);
  EXPECT_EQ(report["stages"]["mesh"]["cloud_points"].get<size_t>(), 15000u);

  // A tiny cloud now: the stage fails naming the file and the cause; mesh/ stays as it was.
  const auto size_before = fs::file_size(survey.mesh() / "mesh.ply");
  ASSERT_TRUE(
      open3d::io::WritePointCloud((survey.dense() / "fused.ply").string(), terrainCloud(10)));
  try {
    runMeshStage(survey, options);
    FAIL() << "a 10-point cloud was accepted";
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "mesh");
    EXPECT_NE(std::string(e.what()).find("10 points"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fused.ply"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::file_size(survey.mesh() / "mesh.ply"), size_before);
  EXPECT_EQ(scene::readMesh(survey.mesh() / "mesh.ply", "test").triangles_.size(),
            summary.stats.triangles);

  // A file that is not a cloud: the error names it.
  std::ofstream(survey.dense() / "fused.ply") << "not a ply";
  try {
    runMeshStage(survey, options);
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("fused.ply"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::file_size(survey.mesh() / "mesh.ply"), size_before);
}

TEST(MeshStage, OptionsBindToFlagsAndTheConfigSection) {
  TempDir dir;
  const fs::path config = dir.path / "recon.yaml";
  std::ofstream(config) << "mesh:\n  density_quantile: 0.05\n  write_untrimmed: false\n";
  MeshStageOptions options;
  OptionSet set("mesh");
  options.bind(set);
  ASSERT_TRUE(set.parse({"--config", config.string(), "--poisson-depth", "7"}));
  EXPECT_EQ(options.surface.poisson_depth, 7);
  EXPECT_DOUBLE_EQ(options.surface.density_quantile, 0.05);
  EXPECT_FALSE(options.write_untrimmed);
  std::ofstream(config) << "mesh:\n  poisson_dept: 8\n";
  MeshStageOptions other;
  OptionSet set2("mesh");
  other.bind(set2);
  EXPECT_THROW(set2.parse({"--config", config.string()}), std::invalid_argument);
}

// Open3D's PLY and OBJ readers trust the file: these crashed them (a polygon's corner past the
// vertices, a face without corners, a list of lists, a texture before the first newmtl of the
// material library), exhausted the memory (a vertex count the file cannot hold) or never ended
// (an element without properties). Each is now a StageError naming the file, and false from
// readTriangleMesh / readPointCloud (inputs in fuzz/regressions/recon_mesh/).
TEST(MeshIo, FilesOpen3dCannotReadSafelyAreStageErrorsNamingTheFile) {
  TempDir dir;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\n";
  const std::string vertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
  const std::string faces = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {header + faces + vertices + "4 0 1 2 100000000\n", "refers to vertex 100000000 of 4"},
      {header + faces + vertices + "3 0 1 7\n", "refers to vertex 7 of 4"},
      {header + faces + vertices + "0\n", "face 0 has 0 corners"},
      {header + "element face 1\nproperty list int list vertex_indices\nend_header\n" + vertices +
           "3 0 1 2\n",
       "list of lists"},
      {"ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n",
       "declares 99999999999 'vertex' elements"},
      {header + "element junk 999999999999\nend_header\n" + vertices,
       "element 'junk' has 999999999999 instances but no property"},
  };
  const fs::path ply = dir.path / "bad.ply";
  for (const auto& [text, message] : cases) {
    std::ofstream(ply, std::ios::trunc) << text;
    try {
      scene::readMesh(ply, "test");
      ADD_FAILURE() << "read: " << text;
    } catch (const StageError& e) {
      EXPECT_NE(std::string(e.what()).find(ply.string() + ": cannot read the mesh: "),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
    o3d::TriangleMesh mesh;
    EXPECT_FALSE(scene::readTriangleMesh(ply, mesh));
  }
  std::ofstream(ply, std::ios::trunc) << cases[4].first;  // the cloud reader: the same count
  EXPECT_THROW(scene::readCloud(ply, "test", "dense"), StageError);

  const fs::path obj = dir.path / "bad.obj";
  std::ofstream(obj) << "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir.path / "bad.mtl") << "# no newmtl\nmap_Kd bad.png\n";
  try {
    scene::readMesh(obj, "test");
    ADD_FAILURE() << "read a material library without newmtl";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.mtl: 'map_Kd' before the first newmtl"),
              std::string::npos)
        << e.what();
  }
  // A quad with its corners in range is still read, as two triangles; so is the OBJ once its
  // material library starts with newmtl.
  std::ofstream(ply, std::ios::trunc) << header + faces + vertices + "4 0 1 2 3\n";
  EXPECT_EQ(scene::readMesh(ply, "test").triangles_.size(), 2u);
  std::ofstream(dir.path / "bad.mtl", std::ios::trunc) << "newmtl a\nKd 1 1 1\n";
  EXPECT_EQ(scene::readMesh(obj, "test").triangles_.size(), 1u);
}
