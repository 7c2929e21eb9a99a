// The scene model and its files: COLMAP text round trip and conventions, camera projection.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/calib3d.hpp>
#include <random>

#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;
using namespace auv::recon::scene;

namespace {
struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_scene_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

/// Two cameras, three images looking at a few points, keypoints where the points project.
Reconstruction smallScene() {
  Reconstruction r;
  r.cameras[1] = Camera::pinhole(1, 640, 480, 500, 510, 319.5, 239.5);
  Camera distorted = Camera::pinhole(2, 800, 600, 600, 600, 400, 300);
  distorted.model = CameraModel::OPENCV;
  distorted.distortion = {0.08, 0.02, 0.001, -0.002};
  r.cameras[2] = distorted;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (uint64_t id = 1; id <= 20; ++id) {
    Point3D p;
    p.id = id;
    p.xyz = Eigen::Vector3d(u(random), u(random), 5 + u(random));
    p.rgb << 10, static_cast<uint8_t>(id), 200;
    r.points[id] = p;
  }
  for (uint32_t id = 1; id <= 3; ++id) {
    Image image;
    image.id = id;
    image.camera_id = id == 3 ? 2 : 1;
    image.name = "cam" + std::to_string(image.camera_id) + "/frame_" + std::to_string(id) + ".png";
    image.q_cw = Eigen::AngleAxisd(0.05 * id, Eigen::Vector3d(0.2, 1, 0.1).normalized());
    image.t_cw = Eigen::Vector3d(0.3 * id, -0.1, 0.05);
    image.points2d.emplace_back(1, 2);  // a keypoint without a point
    image.point3d_ids.push_back(kNoPoint3D);
    for (auto& [pid, p] : r.points) {
      image.points2d.push_back(r.cameras[image.camera_id].project(image.toCamera(p.xyz)));
      image.point3d_ids.push_back(static_cast<int64_t>(pid));
      p.track.push_back({id, static_cast<uint32_t>(image.points2d.size() - 1)});
    }
    r.images[id] = image;
  }
  r.updatePointErrors();
  return r;
}
}  // namespace

TEST(ColmapText, RoundTripKeepsEverything) {
  TempDir dir;
  const Reconstruction r = smallScene();
  EXPECT_LT(r.meanReprojectionError(), 1e-9);
  EXPECT_DOUBLE_EQ(r.meanTrackLength(), 3.0);
  writeColmapText(r, dir.path / "sparse");
  const Reconstruction back = readColmapText(dir.path / "sparse");
  ASSERT_EQ(back.cameras.size(), 2u);
  ASSERT_EQ(back.images.size(), 3u);
  ASSERT_EQ(back.points.size(), 20u);
  EXPECT_EQ(back.cameras.at(2).model, CameraModel::OPENCV);
  EXPECT_NEAR(back.cameras.at(1).cx, 319.5, 1e-12);
  EXPECT_EQ(back.cameras.at(2).distortion, r.cameras.at(2).distortion);
  for (const auto& [id, image] : r.images) {
    const Image& b = back.images.at(id);
    EXPECT_EQ(b.name, image.name);
    EXPECT_LT((b.center() - image.center()).norm(), 1e-12);
    EXPECT_EQ(b.point3d_ids, image.point3d_ids);
    EXPECT_LT((b.points2d[5] - image.points2d[5]).norm(), 1e-9);
  }
  EXPECT_EQ(back.points.at(7).track, r.points.at(7).track);
  EXPECT_EQ(back.points.at(7).rgb, r.points.at(7).rgb);
  EXPECT_LT(back.meanReprojectionError(), 1e-6);
}

TEST(ColmapText, FilesUseColmapsPixelCentres) {
  TempDir dir;
  writeColmapText(smallScene(), dir.path);
  std::ifstream in(dir.path / "cameras.txt");
  std::string line;
  while (std::getline(in, line) && line[0] == '#') {
  }
  EXPECT_EQ(line, "1 PINHOLE 640 480 500 510 320 240");
  std::ifstream images(dir.path / "images.txt");
  while (std::getline(images, line) && line[0] == '#') {
  }
  std::getline(images, line);  // keypoints of image 1: the first is (1, 2) in memory
  EXPECT_EQ(line.rfind("1.5 2.5 -1 ", 0), 0u) << line;
}

TEST(ColmapText, ReadsTheSimulatorsGroundTruthLayout) {
  TempDir dir;
  std::ofstream(dir.path / "cameras.txt")
      << "# comment\n1 OPENCV 2704 2028 1500 1500 1352.5 1014.5 0.08 0.02 0 0\n"
         "3 FULL_OPENCV 960 720 700 700 480.5 360.5 0.1 0.01 0 0 0.001 0 0 0\n";
  std::ofstream(dir.path / "images_left.txt")
      << "1000001 1 0 0 0 0.5 -1 2 1 left_0001.mp4#0\n\n"
         "1000002 0.7071067811865476 0 0.7071067811865476 0 0 0 0 1 left_0001.mp4#1\n\n";
  const auto cameras = readColmapCameras(dir.path / "cameras.txt");
  EXPECT_DOUBLE_EQ(cameras.at(1).cx, 1352.0);
  EXPECT_EQ(cameras.at(3).distortion.size(), 8u);
  const auto images = readColmapImages(dir.path / "images_left.txt");
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images.at(1000001).name, "left_0001.mp4#0");
  EXPECT_LT((images.at(1000001).center() - Eigen::Vector3d(-0.5, 1, -2)).norm(), 1e-12);
  EXPECT_TRUE(images.at(1000002).points2d.empty());
}

TEST(ColmapText, ErrorsNameTheFileAndLine) {
  TempDir dir;
  const fs::path file = dir.path / "cameras.txt";
  std::ofstream(file) << "# header\n1 PINHOLE 640 480 500 500 320\n";
  try {
    readColmapCameras(file);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ":2: PINHOLE needs 4 PARAMS, got 3");
  }
  std::ofstream(file) << "1 FISHEYE 640 480 500 500 320 240\n";
  EXPECT_THROW(readColmapCameras(file), std::runtime_error);
  std::ofstream(dir.path / "images.txt") << "1 1 0 0 0 0 0 0 1 a.png\n1.0 2.0\n";
  try {
    readColmapImages(dir.path / "images.txt");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("images.txt:2: keypoints must come as X Y POINT3D_ID"),
              std::string::npos)
        << e.what();
  }
}

TEST(ColmapText, AnInconsistentModelIsRefused) {
  TempDir dir;
  Reconstruction r = smallScene();
  r.points.at(4).track.push_back({2, 0});  // keypoint 0 of image 2 has no point
  writeColmapText(r, dir.path);
  EXPECT_THROW(readColmapText(dir.path), std::runtime_error);
}

TEST(Camera, ProjectionMatchesOpenCvWithDistortionAndInverts) {
  Camera c = Camera::pinhole(1, 1000, 800, 700, 710, 500, 390);
  c.model = CameraModel::FULL_OPENCV;
  c.distortion = {0.1, -0.05, 0.002, -0.001, 0.01, 0.02, 0.003, 0.001};
  std::vector<cv::Point3d> points = {{0.3, -0.2, 2}, {-0.5, 0.4, 1.5}, {0.01, 0.02, 3}};
  std::vector<cv::Point2d> expected;
  cv::Mat K = (cv::Mat_<double>(3, 3) << 700, 0, 500, 0, 710, 390, 0, 0, 1);
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, cv::Mat(c.distortion),
                    expected);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p(points[i].x, points[i].y, points[i].z);
    const Eigen::Vector2d pixel = c.project(p);
    EXPECT_NEAR(pixel.x(), expected[i].x, 1e-9);
    EXPECT_NEAR(pixel.y(), expected[i].y, 1e-9);
    const Eigen::Vector2d n = c.pixelToNormalized(pixel);
    EXPECT_NEAR(n.x(), p.x() / p.z(), 1e-9);
    EXPECT_NEAR(n.y(), p.y() / p.z(), 1e-9);
  }
}

TEST(Ply, WritesAHeaderAndBinaryBody) {
  TempDir dir;
  PlyData data;
  data.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  data.colors.assign(3, Eigen::Matrix<uint8_t, 3, 1>(255, 0, 0));
  data.triangles = {{0, 1, 2}};
  writePly(dir.path / "t.ply", data);
  std::ifstream in(dir.path / "t.ply", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const size_t end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(text.find("element vertex 3"), std::string::npos);
  EXPECT_NE(text.find("element face 1"), std::string::npos);
  EXPECT_EQ(text.size() - end - 11, 3 * (12 + 3) + (1 + 12));
  data.triangles = {{0, 1, 3}};
  EXPECT_THROW(writePly(dir.path / "bad.ply", data), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir.path / "bad.ply"));
}
