// `auv recon compare` on two synthetic surveys of a rolling seabed (NED, z down): the second
// with a 1 m block (3 × 3 m) and 0.3 m of growth (4 × 4 m), its navigation frame off by
// 0.2 m. The two changes come out as the only two regions, with their areas and volumes;
// change/ holds changes.ply (scalar fields) and report.json. A missing dense cloud names the
// stage to run, surveys of two places are refused; neither writes anything.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "auv/recon/change/compare_stage.h"
#include "auv/recon/change/synthetic_site.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/scene/mesh_io.h"

#include <open3d/geometry/TriangleMesh.h>
#include <opencv2/imgcodecs.hpp>

namespace fs = std::filesystem;

namespace auv::recon::change {
namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() /
           ("compare_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  static inline int counter = 0;
};

/// A survey folder of the synthetic site (change/synthetic_site.h).
Survey survey(const fs::path& root, bool changed, const Eigen::Vector3d& offset, unsigned seed,
              bool with_mesh = false) {
  SyntheticSurvey options;
  options.changed = changed;
  options.offset = offset;
  options.seed = seed;
  options.with_mesh = with_mesh;
  writeSyntheticSurvey(root, options);
  return Survey(root);
}

TEST(CompareStage, FindsTheBlockAndTheGrowthAndNothingElse) {
  TempDir dir;
  const Survey first = survey(dir.path / "s1", false, Eigen::Vector3d::Zero(), 1);
  const Survey second = survey(dir.path / "s2", true, Eigen::Vector3d(0.2, -0.1, 0.05), 2, true);
  CompareOptions options;
  options.later = second.root().string();
  options.detection_scale = 1.0;  // one scale (the default's two: the next test)
  const CompareStage stage;
  const StageReport printed = stage.runWith(first, options);
  const nlohmann::json r =
      nlohmann::json::parse(std::ifstream(second.root() / "change" / "report.json"));
  EXPECT_LT(r["registration"]["rms_m"].get<double>(), 0.02);
  EXPECT_NEAR(r["registration"]["transform_2_to_1"][0][3].get<double>(), -0.2, 0.01);
  ASSERT_EQ(r["clusters"].size(), 2u) << r["clusters"].dump(1);
  // Largest first: the growth (16 m², 0.3 m up: normals point up, NED -z), then the block.
  const auto& growth = r["clusters"][0];
  const auto& block = r["clusters"][1];
  // Areas: at least the true one, at most grown by the cylinder's radius all round (core
  // points whose cylinder reaches over the edge see part of the change).
  const double d = options.m3c2.projection_scale_m;
  EXPECT_GE(growth["area_m2"].get<double>(), 16.0);
  EXPECT_LE(growth["area_m2"].get<double>(), (4.0 + d) * (4.0 + d));
  EXPECT_NEAR(growth["mean_distance_m"].get<double>(), 0.3, 0.05);
  EXPECT_NEAR(growth["volume_gained_m3"].get<double>(), 4.8, 0.2 * 4.8);
  EXPECT_NEAR(growth["centroid"][0].get<double>(), -4.0, 0.3);
  EXPECT_GE(block["area_m2"].get<double>(), 9.0);
  EXPECT_LE(block["area_m2"].get<double>(), (3.0 + d) * (3.0 + d));
  EXPECT_NEAR(block["volume_gained_m3"].get<double>(), 9.0, 0.2 * 9.0);
  EXPECT_NEAR(block["max_abs_distance_m"].get<double>(), 1.0, 0.05);
  EXPECT_NEAR(block["centroid"][0].get<double>(), 3.5, 0.3);
  EXPECT_LT(block["volume_lost_m3"].get<double>(), 0.1);
  // The appearance: survey 2's light taken out, the bleached patch (4 × 4 m, no change of
  // shape) the one region; the block and the growth are left to the shape's comparison.
  const auto& colour = r["appearance"];
  ASSERT_TRUE(colour["measured"].get<bool>()) << colour.dump(1);
  EXPECT_NEAR(colour["normalisation"]["gain_rgb"][0].get<double>(), 1.0 / 1.15, 0.05);
  EXPECT_LT(colour["median_delta_e"].get<double>(), 3.0);
  ASSERT_EQ(colour["clusters"].size(), 1u) << colour["clusters"].dump(1);
  EXPECT_NEAR(colour["clusters"][0]["centroid"][0].get<double>(), -4.0, 0.3);
  EXPECT_NEAR(colour["clusters"][0]["centroid"][1].get<double>(), 5.0, 0.3);
  EXPECT_GE(colour["clusters"][0]["area_m2"].get<double>(), 0.8 * 16.0);
  // At most grown by the colour radius (0.2 m) all round and a core spacing.
  EXPECT_LE(colour["clusters"][0]["area_m2"].get<double>(), (4.0 + 0.6) * (4.0 + 0.6));
  // The files a viewer and the next tools read.
  std::ifstream ply(second.root() / "change" / "changes.ply", std::ios::binary);
  std::string header((std::istreambuf_iterator<char>(ply)), {});
  header = header.substr(0, header.find("end_header"));
  EXPECT_NE(header.find("property float scalar_distance"), std::string::npos) << header;
  EXPECT_NE(header.find("property float scalar_level_of_detection"), std::string::npos);
  EXPECT_EQ(readReportSection(second.report(), "compare")["clusters"].get<size_t>(), 2u);
  // The 3-D view: the coloured mesh drawn over a white background, red on the block.
  const cv::Mat view = cv::imread((second.root() / "change" / "change_view.png").string());
  ASSERT_FALSE(view.empty());
  size_t red = 0, background = 0;
  for (int y = 0; y < view.rows; ++y) {
    for (int x = 0; x < view.cols; ++x) {
      const cv::Vec3b p = view.at<cv::Vec3b>(y, x);
      red += p[2] > 150 && p[0] < 60 && p[1] < 60;
      background += p == cv::Vec3b(255, 255, 255);
    }
  }
  EXPECT_GT(red, 2000u) << "the block and the growth, in red";
  EXPECT_GT(background, 1000u);
  EXPECT_LT(background, static_cast<size_t>(view.total()) * 9 / 10);
  // The top-down map: north up, east right, 0.2 m cells of 4 px from (x, y) = (10, -10).
  const cv::Mat map = cv::imread((second.root() / "change" / "change_map.png").string());
  ASSERT_FALSE(map.empty());
  const auto pixel = [&](double x, double y) {
    return map.at<cv::Vec3b>(static_cast<int>((10.0 - x) / 0.2) * 4 + 2,
                             static_cast<int>((y + 10.0) / 0.2) * 4 + 2);
  };
  const cv::Vec3b on_block = pixel(3.5, 2.5), on_seabed = pixel(-8.0, 8.0);
  EXPECT_GT(on_block[2], 200) << "red";  // BGR
  EXPECT_LT(on_block[0], 60) << "the block is shown at full red";
  EXPECT_GT(on_seabed[0], 150) << "the unchanged seabed stays pale";
  EXPECT_GT(on_seabed[2], 150);
  // Survey 2's mesh, coloured by the change, in survey 1's frame.
  ASSERT_EQ(r["coloured_mesh"], "mesh_change.ply");
  open3d::geometry::TriangleMesh mesh;
  ASSERT_TRUE(scene::readTriangleMesh(second.root() / "change" / "mesh_change.ply", mesh));
  ASSERT_TRUE(mesh.HasVertexColors());
  size_t block_vertices = 0, block_red = 0;
  for (size_t v = 0; v < mesh.vertices_.size(); ++v) {
    const Eigen::Vector3d& p = mesh.vertices_[v];
    if (onSyntheticBlock(p.x() - 0.3, p.y() - 0.3) && onSyntheticBlock(p.x() + 0.3, p.y() + 0.3)) {
      ++block_vertices;
      block_red += mesh.vertex_colors_[v].x() > 0.9 && mesh.vertex_colors_[v].z() < 0.3;
    }
  }
  ASSERT_GT(block_vertices, 100u);
  EXPECT_GT(static_cast<double>(block_red) / block_vertices, 0.95);
  ASSERT_GE(printed.lines.size(), 3u);
  EXPECT_NE(printed.lines[0].find("2 regions"), std::string::npos) << printed.lines[0];
}

// Two scales (the default): regions found with cylinders twice as wide, measured with d and D —
// the same two regions, volumes as true, each region at most as wide as the coarse cylinder
// blurs.
TEST(CompareStage, AtTwoScalesTheRegionsAreFoundCoarseAndMeasuredFine) {
  TempDir dir;
  const Survey first = survey(dir.path / "s1", false, Eigen::Vector3d::Zero(), 1);
  const Survey second = survey(dir.path / "s2", true, Eigen::Vector3d(0.2, -0.1, 0.05), 2);
  CompareOptions options;
  options.later = second.root().string();
  options.detection_scale = 2.0;
  runCompare(first, options);
  const nlohmann::json r =
      nlohmann::json::parse(std::ifstream(second.root() / "change" / "report.json"));
  ASSERT_TRUE(r.contains("detection")) << r.dump(1);
  EXPECT_EQ(r["detection"]["projection_scale_m"].get<double>(),
            2.0 * options.m3c2.projection_scale_m);
  ASSERT_EQ(r["clusters"].size(), 2u) << r["clusters"].dump(1);
  const auto& growth = r["clusters"][0];
  const auto& block = r["clusters"][1];
  const double d = 2.0 * options.m3c2.projection_scale_m;
  EXPECT_GE(block["area_m2"].get<double>(), 9.0);
  EXPECT_LE(block["area_m2"].get<double>(), (3.0 + d) * (3.0 + d));
  EXPECT_NEAR(block["volume_gained_m3"].get<double>(), 9.0, 0.2 * 9.0);
  EXPECT_NEAR(block["max_abs_distance_m"].get<double>(), 1.0, 0.05);
  EXPECT_NEAR(growth["volume_gained_m3"].get<double>(), 4.8, 0.2 * 4.8);
  std::ifstream ply(second.root() / "change" / "changes.ply", std::ios::binary);
  std::string header((std::istreambuf_iterator<char>(ply)), {});
  header = header.substr(0, header.find("end_header"));
  EXPECT_NE(header.find("property float scalar_detection_distance"), std::string::npos) << header;
  CompareOptions bad = options;
  bad.detection_scale = 0.5;
  EXPECT_THROW(bad.check(), OptionError);
}

/// CloudCompare's path, or empty when it is not installed.
std::string cloudCompare() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin"}) {
    const fs::path candidate = fs::path(dir) / "CloudCompare";
    if (fs::exists(candidate)) return candidate.string();
  }
  return "";
}

TEST(CompareStage, CloudCompareReadsTheChangesAsScalarFields) {
  const std::string tool = cloudCompare();
  if (tool.empty()) GTEST_SKIP() << "CloudCompare is not installed (scripts/install-deps.sh)";
  TempDir dir;
  const Survey first = survey(dir.path / "s1", false, Eigen::Vector3d::Zero(), 6);
  const Survey second = survey(dir.path / "s2", true, Eigen::Vector3d::Zero(), 7);
  CompareOptions options;
  options.later = second.root().string();
  const nlohmann::json r = runCompare(first, options);
  // The reference reader: CloudCompare's command-line mode, exported as ASCII with a header.
  const fs::path exported = dir.path / "changes.asc";
  const std::string command = "QT_QPA_PLATFORM=offscreen '" + tool + "' -SILENT -O '" +
                              (second.root() / "change" / "changes.ply").string() +
                              "' -C_EXPORT_FMT ASC -ADD_HEADER -SAVE_CLOUDS FILE '" +
                              exported.string() + "' > '" + (dir.path / "cc.log").string() +
                              "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(exported);
  std::string header;
  std::getline(in, header);
  // "//X Y Z <scalar fields> Nx Ny Nz": the columns by name.
  std::istringstream names(header.substr(2));
  std::vector<std::string> columns;
  for (std::string name; names >> name;) columns.push_back(name);
  const auto column = [&](const std::string& name) {
    const auto at = std::find(columns.begin(), columns.end(), name);
    return at == columns.end() ? -1 : static_cast<int>(at - columns.begin());
  };
  const int distance_at = column("distance"), lod_at = column("level_of_detection"),
            flag_at = column("significant");
  ASSERT_GE(distance_at, 0) << header;
  ASSERT_GE(lod_at, 0) << header;
  ASSERT_GE(flag_at, 0) << header;
  size_t rows = 0, significant = 0, measured = 0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::vector<std::string> values;
    for (std::string value; fields >> value;) values.push_back(value);
    ASSERT_EQ(values.size(), columns.size()) << line;
    ++rows;
    const bool flag = std::stod(values[flag_at]) == 1.0;
    significant += flag;
    if (values[distance_at] != "nan") {
      ++measured;
      EXPECT_EQ(flag, std::abs(std::stod(values[distance_at])) > std::stod(values[lod_at])) << line;
    }
  }
  EXPECT_EQ(rows, r["core_points"].get<size_t>());
  EXPECT_EQ(measured, r["core_points_measured"].get<size_t>());
  EXPECT_EQ(significant, r["core_points_significant"].get<size_t>());
}

TEST(CompareStage, AMissingCloudNamesTheStageToRunAndWritesNothing) {
  TempDir dir;
  const Survey first = survey(dir.path / "s1", false, Eigen::Vector3d::Zero(), 3);
  fs::create_directories(dir.path / "s2");
  CompareOptions options;
  options.later = (dir.path / "s2").string();
  try {
    runCompare(first, options);
    FAIL() << "compared with a survey that has no dense cloud";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("fused.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dense"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path / "s2" / "change"));
}

TEST(CompareStage, SurveysOfTwoPlacesAreRefusedAndNothingIsWritten) {
  TempDir dir;
  const Survey first = survey(dir.path / "s1", false, Eigen::Vector3d::Zero(), 4);
  const Survey second = survey(dir.path / "s2", false, Eigen::Vector3d(200.0, 0.0, 0.0), 5);
  CompareOptions options;
  options.later = second.root().string();
  try {
    runCompare(first, options);
    FAIL() << "compared two places 200 m apart";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("overlap too little"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(second.root() / "change"));
  EXPECT_TRUE(readReport(second.report()).empty());
  options.later.clear();
  EXPECT_THROW(runCompare(first, options), OptionError);
}

}  // namespace
}  // namespace auv::recon::change
