// Folder -> scene: the layers and counts of a demo survey and a demo run in the real formats,
// levels of detail, and every bad input named (folder, file:line, column).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <set>

#include "auv/config/errors.h"
#include "auv/view/folder.h"
#include "auv/view/mesh.h"
#include "auv/view/options.h"
#include "child.h"
#include "fixtures.h"

namespace auv::view {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

fs::path tempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("auv_view_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

const json& layer(const Scene& scene, const std::string& id) {
  for (const auto& l : scene.manifest["layers"]) {
    if (l["id"] == id) return l;
  }
  static const json none;
  ADD_FAILURE() << "no layer " << id << " in " << scene.manifest.dump();
  return none;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "(no ConfigError)";
}

TEST(SurveyScene, HasEveryLayerInTheTruthsFrame) {
  const fs::path survey = tempDir("survey");
  const auto counts = test::writeDemoSurvey(survey);
  EXPECT_EQ(detectFolder(survey), FolderKind::kSurvey);
  const Scene scene = buildSurveyScene(survey, SceneOptions{});
  EXPECT_EQ(scene.manifest["kind"], "survey");
  EXPECT_NE(scene.manifest["frame"].get<std::string>().find("world"), std::string::npos);
  EXPECT_EQ(scene.manifest["model"]["triangles"], counts.triangles);
  EXPECT_EQ(layer(scene, "model_0")["count"], counts.triangles);
  EXPECT_EQ(layer(scene, "dense")["count"], counts.dense_points);
  EXPECT_EQ(layer(scene, "sparse")["count"], counts.sparse_points);
  EXPECT_EQ(layer(scene, "cameras")["count"], counts.cameras);
  EXPECT_EQ(layer(scene, "cameras")["cameras"], json({"left", "right"}));
  EXPECT_EQ(layer(scene, "contribution")["count"], counts.dense_points);
  EXPECT_EQ(layer(scene, "trajectory_sfm")["count"], 2);  // one line per camera
  // Navigation and truth clipped to the recordings' 5-30 s (+-5 s) of a 0-40 s run.
  EXPECT_EQ(layer(scene, "trajectory_estimated")["poses"], 36);
  EXPECT_EQ(layer(scene, "trajectory_true")["poses"], 36);
  // Every buffer the manifest names exists, sized as described; the texture is a served file.
  for (const auto& l : scene.manifest["layers"]) {
    const auto blob = scene.blobs.find(l["url"].get<std::string>());
    ASSERT_NE(blob, scene.blobs.end()) << l["url"];
    EXPECT_EQ(blob->second.bytes.size(), l["bytes"].get<size_t>());
  }
  const json& groups = layer(scene, "model_0")["groups"];
  ASSERT_EQ(groups.size(), 2u);  // two atlas pages
  for (int k = 0; k < 2; ++k) {
    const std::string texture = groups[k]["texture"];
    ASSERT_TRUE(scene.files.count(texture));
    EXPECT_EQ(scene.files.at(texture).filename(), "model_" + std::to_string(k) + ".png");
  }
  EXPECT_EQ(groups[0]["count"].get<size_t>() + groups[1]["count"].get<size_t>(),
            3 * counts.triangles);
}

TEST(SurveyScene, WithoutEvaluationStaysInTheReconstructionsFrame) {
  const fs::path survey = tempDir("survey_sfm");
  test::writeDemoSurvey(survey);
  fs::remove(survey / "evaluation.json");
  const Scene scene = buildSurveyScene(survey, SceneOptions{});
  EXPECT_EQ(scene.manifest["frame"], "reconstruction (SfM)");
  const std::string notes = scene.manifest["notes"].dump();
  EXPECT_NE(notes.find("auv recon evaluate"), std::string::npos) << notes;
  EXPECT_NE(notes.find("figures/cameras.ply"), std::string::npos) << notes;  // frames differ
}

TEST(RunScene, HasMapTreesPathsTrajectoriesAndCollisions) {
  const fs::path run = tempDir("run");
  const auto counts = test::writeDemoRun(run);
  EXPECT_EQ(detectFolder(run), FolderKind::kRun);
  const Scene scene = buildRunScene(run, SceneOptions{});
  EXPECT_EQ(scene.manifest["kind"], "run");
  EXPECT_EQ(layer(scene, "map")["count"], counts.voxels);
  EXPECT_EQ(layer(scene, "map")["resolution"], 0.5);
  EXPECT_EQ(layer(scene, "trees")["count"], counts.tree_edges);
  EXPECT_EQ(layer(scene, "trees")["trees"], 2);
  EXPECT_EQ(layer(scene, "paths")["count"], counts.paths);
  EXPECT_EQ(layer(scene, "waypoints")["count"], counts.waypoints);
  EXPECT_EQ(layer(scene, "collisions")["count"], counts.collisions);
  EXPECT_EQ(layer(scene, "trajectory_true")["poses"], 101);
  EXPECT_EQ(layer(scene, "trajectory_estimated")["poses"], 101);
  // The last path of query 1 is its path_seq 2 (3 vertices), not the first one.
  const auto& paths = scene.blobs.at(layer(scene, "paths")["url"]).bytes;
  const json& arrays = layer(scene, "paths")["arrays"];
  EXPECT_EQ(arrays["position"]["count"], 5);
  uint32_t vertices[2];
  std::memcpy(vertices, paths.data() + arrays["vertices"]["offset"].get<size_t>(), 8);
  EXPECT_EQ(vertices[0], 3u);
  EXPECT_EQ(vertices[1], 2u);
}

TEST(Folder, NeitherSurveyNorRunIsNamed) {
  const fs::path empty = tempDir("empty");
  std::string what = errorOf([&] { detectFolder(empty); });
  EXPECT_NE(what.find(empty.string()), std::string::npos) << what;
  EXPECT_NE(what.find("neither a survey"), std::string::npos) << what;
  what = errorOf([&] { detectFolder(empty / "missing"); });
  EXPECT_NE(what.find("no such folder"), std::string::npos) << what;
  std::ofstream(empty / "file.txt") << "x";
  what = errorOf([&] { detectFolder(empty / "file.txt"); });
  EXPECT_NE(what.find("not a folder"), std::string::npos) << what;
}

TEST(RunScene, BadFilesAreNamedWithLineAndColumn) {
  const fs::path run = tempDir("bad_run");
  test::writeDemoRun(run);
  std::ofstream(run / "mission" / "paths.csv", std::ios::app) << "10,2,4,0,abc,1,3\n";
  std::string what = errorOf([&] { buildRunScene(run, SceneOptions{}); });
  EXPECT_NE(what.find("paths.csv:9: x: expected a number, got 'abc'"), std::string::npos) << what;
  test::writeDemoRun(run);
  std::ofstream(run / "mission" / "waypoints.csv") << "t,query_id,x,y\n1,1,2,3\n";
  what = errorOf([&] { buildRunScene(run, SceneOptions{}); });
  EXPECT_NE(what.find("waypoints.csv: no column 'z'"), std::string::npos) << what;
  test::writeDemoRun(run);
  std::ofstream(run / "mission" / "map.bt") << "not an octomap";
  what = errorOf([&] { buildRunScene(run, SceneOptions{}); });
  EXPECT_NE(what.find("map.bt: not an OctoMap file"), std::string::npos) << what;
}

TEST(ObjReader, BadModelsAreNamed) {
  const fs::path dir = tempDir("bad_obj");
  std::ofstream(dir / "a.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
  std::string what = errorOf([&] { readObj(dir / "a.obj"); });
  EXPECT_NE(what.find("a.obj:4: bad face corner"), std::string::npos) << what;
  std::ofstream(dir / "b.obj") << "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "b.mtl") << "newmtl m\nmap_Kd ../../etc/passwd\n";
  what = errorOf([&] { readObj(dir / "b.obj"); });
  EXPECT_NE(what.find("lies outside"), std::string::npos) << what;
  std::ofstream(dir / "b.mtl") << "newmtl m\nmap_Kd missing.png\n";
  what = errorOf([&] { readObj(dir / "b.obj"); });
  EXPECT_NE(what.find("b.mtl:2: texture 'missing.png' not found"), std::string::npos) << what;
  std::ofstream(dir / "c.obj") << "v 0 0\n";
  what = errorOf([&] { readObj(dir / "c.obj"); });
  EXPECT_NE(what.find("c.obj:1: expected 'v x y z'"), std::string::npos) << what;
}

TEST(MeshLevels, HalfEachKeepingTextureCoordinatesAndPages) {
  const fs::path survey = tempDir("levels");
  test::writeTerrainSurvey(survey, 80000, 2);
  const TexturedMesh mesh = readObj(survey / "textured" / "model.obj");
  EXPECT_NEAR(static_cast<double>(mesh.triangles()), 80000, 1000);
  const auto levels = buildLevels(mesh, 5000);
  ASSERT_GE(levels.size(), 5u);
  std::set<std::pair<float, float>> original;
  for (size_t i = 0; i < mesh.uv.size(); i += 2) original.insert({mesh.uv[i], mesh.uv[i + 1]});
  for (size_t k = 1; k < levels.size(); ++k) {
    const TexturedMesh& m = levels[k].mesh;
    EXPECT_LE(m.triangles(), levels[k - 1].mesh.triangles() * 0.6) << "level " << k;
    EXPECT_GE(m.triangles(), levels[k - 1].mesh.triangles() * 0.4) << "level " << k;
    ASSERT_EQ(m.groups.size(), 2u);  // both pages kept, each triangle on its own
    for (int g = 0; g < 2; ++g) EXPECT_EQ(m.groups[g].texture, mesh.groups[g].texture);
    // A page's triangles use only that page's texture coordinates (rows 0-1/2 or 1/2-1).
    for (size_t i = m.groups[1].first_index; i < m.groups[1].first_index + m.groups[1].index_count;
         ++i) {
      ASSERT_GE(m.uv[2 * m.index[i] + 1], 0.5f - 1e-6f) << "level " << k;
    }
    // Edge collapse keeps existing vertices: every (u, v) is one of the original's.
    for (size_t i = 0; i < m.uv.size(); i += 2) {
      ASSERT_TRUE(original.count({m.uv[i], m.uv[i + 1]})) << "level " << k;
    }
    for (uint32_t v : m.index) ASSERT_LT(v, m.position.size() / 3);
  }
  EXPECT_LE(levels.back().mesh.triangles(), 5000u);
}

TEST(MeshLevels, AnAtlasOfAPatchPerFaceGoesOnAsVertexColours) {
  const fs::path survey = tempDir("patches");
  test::writeTerrainSurvey(survey, 20000, 2, /*patch_per_face=*/true);
  const TexturedMesh mesh = readObj(survey / "textured" / "model.obj");
  ASSERT_EQ(mesh.position.size() / 3, 3 * mesh.triangles());  // every vertex on a seam
  const auto levels = buildLevels(mesh, 2000);
  ASSERT_GE(levels.size(), 4u);
  EXPECT_TRUE(levels[0].mesh.color.empty());
  for (size_t k = 1; k < levels.size(); ++k) {
    const TexturedMesh& m = levels[k].mesh;
    EXPECT_LE(m.triangles(), levels[k - 1].mesh.triangles() * 0.6) << "level " << k;
    ASSERT_EQ(m.groups.size(), 1u);
    EXPECT_TRUE(m.groups[0].texture.empty());
    EXPECT_TRUE(m.uv.empty());
    ASSERT_EQ(m.color.size(), m.position.size());
    for (uint32_t v : m.index) ASSERT_LT(v, m.position.size() / 3);
  }
  // Each vertex has the atlas's colour where it lies (the grid's uv: x, y over 60 m), but
  // where it meets the checker's edges.
  const TexturedMesh& m = levels[1].mesh;
  size_t close = 0;
  for (size_t v = 0; v < m.position.size() / 3; ++v) {
    uint8_t expected[3];
    test::texel(std::min(static_cast<int>(m.position[3 * v] / 60 * 2048), 2047),
                std::min(static_cast<int>((1 - m.position[3 * v + 1] / 60) * 2048), 2047), 2048,
                expected);
    bool near = true;
    for (int c = 0; c < 3; ++c) near = near && std::abs(m.color[3 * v + c] - expected[c]) <= 12;
    close += near;
  }
  EXPECT_GE(close, m.position.size() / 3 * 9 / 10);
  EXPECT_LE(levels.back().mesh.triangles(), 2000u);
}

TEST(MeshLevels, AnUndecodableAtlasPageLeavesItsVerticesGrey) {
  const fs::path survey = tempDir("patches_bad");
  test::writeTerrainSurvey(survey, 2000, 1, /*patch_per_face=*/true);
  std::ofstream(survey / "textured" / "model_0.png") << "not a png";
  const auto levels = buildLevels(readObj(survey / "textured" / "model.obj"), 200);
  ASSERT_GE(levels.size(), 2u);
  const TexturedMesh& m = levels[1].mesh;
  ASSERT_FALSE(m.color.empty());
  for (uint8_t c : m.color) ASSERT_EQ(c, 160);
}

TEST(MeshTiles, PartitionEveryTriangleOnceWithBoundsThatHoldThem) {
  const fs::path survey = tempDir("tiles");
  test::writeTerrainSurvey(survey, 80000, 2);
  TexturedMesh mesh = readObj(survey / "textured" / "model.obj");
  std::multiset<std::array<uint32_t, 3>> before, after;
  for (size_t i = 0; i < mesh.index.size(); i += 3) {
    before.insert({mesh.index[i], mesh.index[i + 1], mesh.index[i + 2]});
  }
  const std::vector<Tile> tiles = tileMesh(mesh, 5000);
  EXPECT_EQ(tiles.size(), 16u);  // sqrt(80000 / 5000) = 4 per side
  size_t indices = 0;
  for (const Tile& t : tiles) {
    for (const auto& g : t.groups) {
      indices += g.index_count;
      for (size_t i = g.first_index; i < g.first_index + g.index_count; i += 3) {
        after.insert({mesh.index[i], mesh.index[i + 1], mesh.index[i + 2]});
        for (int c = 0; c < 3; ++c) {
          const float* p = &mesh.position[3 * mesh.index[i + c]];
          const float d = std::hypot(p[0] - t.center[0], p[1] - t.center[1], p[2] - t.center[2]);
          ASSERT_LE(d, t.radius * 1.0001f + 1e-4f);
        }
        // A triangle keeps its page: rows of page 1 have v >= 0.5.
        if (g.texture.filename() == "model_1.png") {
          ASSERT_GE(mesh.uv[2 * mesh.index[i] + 1], 0.5f);
        }
      }
    }
  }
  EXPECT_EQ(indices, mesh.index.size());
  EXPECT_EQ(before, after);  // a partition: every triangle once, none new
  const TexturedMesh small = readObj(survey / "textured" / "model.obj");
  TexturedMesh copy = small;
  EXPECT_EQ(tileMesh(copy, 1000000).size(), 1u);
}

TEST(Cli, BadFolderAndOptionsExit2NamingThem) {
  const fs::path empty = tempDir("cli");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  for (const Case& c :
       std::vector<Case>{{{empty.string()}, "neither a survey"},
                         {{(empty / "missing").string()}, "no such folder"},
                         {{empty.string(), "--port", "http"}, "--port: expected an integer"},
                         {{empty.string(), "--frobnicate"}, "unknown option '--frobnicate'"},
                         {{"--live", "http://x"}, "--live: expected a ws:// or wss:// URL"},
                         {{}, "no folder given"}}) {
    std::vector<std::string> argv = {"sh", "-c", std::string(AUV_VIEW_EXE) + " \"$@\" 2>&1", "sh"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    test::Child child(argv);
    std::string output, line;
    while (child.readLine(line, 30)) output += line + "\n";
    EXPECT_EQ(child.wait(), 2) << output;
    EXPECT_NE(output.find(c.message), std::string::npos) << output;
  }
}

}  // namespace
}  // namespace auv::view
