#include "fixtures.h"

#include <array>
#include <cmath>
#include <fstream>

#include <octomap/OcTree.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/ImageIO.h>
#include <open3d/io/PointCloudIO.h>

namespace auv::view::test {
namespace fs = std::filesystem;

void texel(int x, int y, int size, uint8_t rgb[3]) {
  const bool check = ((x * 8 / size) + (y * 8 / size)) % 2 == 0;
  rgb[0] = static_cast<uint8_t>(check ? 220 : 40 + 150 * x / size);
  rgb[1] = static_cast<uint8_t>(check ? 180 : 90);
  rgb[2] = static_cast<uint8_t>(check ? 60 : 40 + 150 * y / size);
}

namespace {

void writeTexture(const fs::path& file, int size) {
  open3d::geometry::Image image;
  image.Prepare(size, size, 3, 1);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) texel(x, y, size, image.PointerAt<uint8_t>(x, y, 0));
  }
  open3d::io::WriteImage(file.string(), image);
}

/// A height field n x n quads over [0, extent]² in x, y (NED: z down); its rows split over
/// `pages` materials (atlas pages model_<k>.png). Texture coordinates are one grid over the
/// terrain, or with `patch_per_face` three of their own per face (the same values), as
/// `auv recon texture` writes them: then every vertex lies on a seam.
size_t writeGridObj(const fs::path& folder, int n, double extent, int pages,
                    bool patch_per_face = false) {
  fs::create_directories(folder);
  std::ofstream mtl(folder / "model.mtl");
  for (int k = 0; k < pages; ++k) {
    mtl << "newmtl page_" << k << "\nKd 1 1 1\nmap_Kd model_" << k << ".png\n";
  }
  std::ofstream obj(folder / "model.obj");
  obj << "mtllib model.mtl\n";
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = extent * i / n, y = extent * j / n;
      const double z = 10 + std::sin(x * 0.3) * std::cos(y * 0.2) * 2;
      obj << "v " << x << " " << y << " " << z << "\n";
    }
  }
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) obj << "vt " << double(i) / n << " " << double(j) / n << "\n";
  }
  int patch_uvs = 0;
  for (int j = 0; j < n; ++j) {
    if (j * pages % n == 0 || j == 0) obj << "usemtl page_" << j * pages / n << "\n";
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
      // Counter-clockwise seen from above (-z in NED): the faces point up, to the cameras.
      for (const std::array<int, 3>& face : {std::array<int, 3>{a, d, b}, {a, c, d}}) {
        std::array<int, 3> vt = face;
        for (int k = 0; k < 3 && patch_per_face; ++k) {
          const int v = face[k] - 1;
          obj << "vt " << double(v % (n + 1)) / n << " " << double(v / (n + 1)) / n << "\n";
          vt[k] = (n + 1) * (n + 1) + ++patch_uvs;
        }
        obj << "f";
        for (int k = 0; k < 3; ++k) obj << " " << face[k] << "/" << vt[k];
        obj << "\n";
      }
    }
  }
  return static_cast<size_t>(2 * n * n);
}

}  // namespace

SurveyCounts writeDemoSurvey(const fs::path& survey) {
  SurveyCounts counts{};
  counts.triangles = writeGridObj(survey / "textured", 4, 8.0, 2);
  writeTexture(survey / "textured" / "model_0.png", 64);
  writeTexture(survey / "textured" / "model_1.png", 32);
  // Dense cloud over the model, coloured.
  open3d::geometry::PointCloud dense;
  for (int i = 0; i < 400; ++i) {
    const double x = (i % 20) * 0.4, y = (i / 20) * 0.4;
    dense.points_.emplace_back(x, y, 10 + std::sin(x * 0.3) * std::cos(y * 0.2) * 2);
    dense.colors_.emplace_back(0.2 + 0.6 * (i % 20) / 20.0, 0.5, 0.3);
  }
  fs::create_directories(survey / "dense");
  open3d::io::WritePointCloud((survey / "dense" / "fused.ply").string(), dense);
  counts.dense_points = dense.points_.size();
  // Per-camera contribution: the same points, red / green / yellow.
  open3d::geometry::PointCloud contribution = dense;
  for (size_t i = 0; i < contribution.colors_.size(); ++i) {
    contribution.colors_[i] = i % 3 == 0   ? Eigen::Vector3d(1, 0, 0)
                              : i % 3 == 1 ? Eigen::Vector3d(0, 1, 0)
                                           : Eigen::Vector3d(1, 1, 0);
  }
  fs::create_directories(survey / "figures");
  open3d::io::WritePointCloud((survey / "figures" / "cameras.ply").string(), contribution);
  std::ofstream(survey / "report.json") << R"({"figures": {"aligned_to_truth": true}})";
  // SfM: two cameras of three poses each, looking down (+z), at 4 m above the model.
  fs::create_directories(survey / "sparse");
  std::ofstream images(survey / "sparse" / "images.txt");
  images << "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n";
  int id = 1;
  for (const char* camera : {"left", "right"}) {
    for (int k = 0; k < 3; ++k, ++id) {
      const Eigen::Vector3d centre(2.0 + 2 * k, camera[0] == 'l' ? 3.0 : 5.0, 6.0);
      const Eigen::Vector3d t = -centre;  // identity rotation: t = -R c
      images << id << " 1 0 0 0 " << t.x() << " " << t.y() << " " << t.z() << " 1 " << camera << "/"
             << camera << "_000" << k << ".png\n\n";
    }
  }
  counts.cameras = 6;
  std::ofstream points(survey / "sparse" / "points3D.txt");
  points << "# POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[]\n";
  for (int i = 0; i < 50; ++i) {
    points << i + 1 << " " << (i % 10) * 0.8 << " " << (i / 10) * 1.6
           << " 10 200 200 200 0.5 1 0\n";
  }
  counts.sparse_points = 50;
  // Evaluated against a simulated run: identity alignment, navigation beside the truth.
  std::ofstream(survey / "evaluation.json")
      << R"({"alignment": {"scale": 1.0, "rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0,0,0]}})";
  std::ofstream(survey / "simulation.json") << R"({"ground_truth_run": "truth"})";
  fs::create_directories(survey / "truth" / "ground_truth");
  std::ofstream nav(survey / "truth" / "ground_truth" / "navigation.tum");
  std::ofstream truth(survey / "truth" / "ground_truth" / "trajectory.tum");
  for (int k = 0; k <= 40; ++k) {
    truth << k << " " << 0.2 * k << " 4 6 0 0 0 1\n";
    nav << k << " " << 0.2 * k << " " << 4 + 0.01 * k << " 6 0 0 0 1\n";
  }
  fs::create_directories(survey / "recordings" / "left");
  std::ofstream frames(survey / "recordings" / "left" / "left_0001.mp4.frames.csv");
  frames << "frame,camera_time_s,sim_time_s\n0,0.0,5.0\n1,0.25,5.25\n2,20.0,30.0\n";
  return counts;
}

RunCounts writeDemoRun(const fs::path& run) {
  RunCounts counts{};
  fs::create_directories(run / "mission");
  fs::create_directories(run / "ground_truth");
  // A wall of 0.5 m voxels and free space in front of it.
  octomap::OcTree map(0.5);
  for (int i = 0; i < 10; ++i) {
    for (int k = 0; k < 4; ++k) {
      map.updateNode(octomap::point3d(10.25f, 0.25f + 0.5f * i, 2.25f + 0.5f * k), true);
      map.updateNode(octomap::point3d(5.25f, 0.25f + 0.5f * i, 2.25f + 0.5f * k), false);
    }
  }
  map.writeBinary((run / "mission" / "map.bt").string());
  counts.voxels = 40;
  std::ofstream tree1(run / "mission" / "tree_1.csv");
  tree1 << "index,parent,x,y,z,cost\n0,-1,0,0,3,0\n1,0,1,1,3,1.4\n2,0,1,-1,3,1.4\n3,1,2,2,3,2.8\n";
  std::ofstream tree2(run / "mission" / "tree_2.csv");
  tree2 << "index,parent,x,y,z,cost\n0,-1,6,2,3,0\n1,0,7,3,3,1.4\n";
  counts.tree_edges = 4;
  std::ofstream paths(run / "mission" / "paths.csv");
  paths << "t,query_id,path_seq,index,x,y,z\n"
        << "1.0,1,1,0,0,0,3\n1.0,1,1,1,2,2,3\n"  // replaced by seq 2
        << "2.0,1,2,0,0,0,3\n2.0,1,2,1,3,1,3\n2.0,1,2,2,6,2,3\n"
        << "9.0,2,3,0,6,2,3\n9.0,2,3,1,8,4,3\n";
  counts.paths = 2;
  std::ofstream waypoints(run / "mission" / "waypoints.csv");
  waypoints << "t,query_id,waypoint_id,x,y,z,is_final\n2.0,1,1,3,1,3,0\n3.0,1,2,6,2,3,1\n";
  counts.waypoints = 2;
  std::ofstream(run / "mission" / "events.csv")
      << "t,event,query_index,query_id,waypoint_id,x,y,z,detail\n0,EXECUTING,0,1,0,0,0,3,\n";
  std::ofstream truth(run / "ground_truth" / "trajectory.tum");
  std::ofstream nav(run / "ground_truth" / "navigation.tum");
  for (int k = 0; k <= 100; ++k) {
    const double x = 0.08 * k, y = 0.04 * k;
    truth << 0.1 * k << " " << x << " " << y << " 3 0 0 0 1\n";
    nav << 0.1 * k << " " << x + 0.002 * k << " " << y << " 3 0 0 0 1\n";
  }
  std::ofstream collisions(run / "ground_truth" / "collisions.csv");
  collisions << "t,x,y,z,normal_x,normal_y,normal_z,penetration,speed,started\n"
             << "7.5,6,3,3,1,0,0,0.05,0.3,1\n";
  counts.collisions = 1;
  return counts;
}

void writeTerrainSurvey(const fs::path& survey, size_t triangles, int pages, bool patch_per_face) {
  const int n = static_cast<int>(std::lround(std::sqrt(triangles / 2.0)));
  writeGridObj(survey / "textured", n, 60.0, pages, patch_per_face);
  for (int k = 0; k < pages; ++k) {
    writeTexture(survey / "textured" / ("model_" + std::to_string(k) + ".png"), 2048);
  }
}

}  // namespace auv::view::test
