// The visual channels' JSON against Foxglove's schemas: map cubes from an OcTree (occupied,
// free and unknown by style, the cap), tree edges as a line list, path as a line strip, the
// vehicle's entities, /tf, a CompressedImage with base64 data, the camera channel names.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "auv/foxglove_bridge/scene.h"

namespace auv::foxglove_bridge {
namespace {

msg::Point point(double x, double y, double z) {
  msg::Point p;
  p.x(x);
  p.y(y);
  p.z(z);
  return p;
}

TEST(Scene, MapCubesFollowTheStyle) {
  octomap::OcTree tree(0.5);
  tree.updateNode(octomap::point3d(1.1, 1.1, 1.1), true);
  tree.updateNode(octomap::point3d(2.1, 1.1, 1.1), true);
  tree.updateNode(octomap::point3d(1.1, 2.1, 1.1), false);
  auto scene = mapScene(tree, {}, 1500000000);
  const auto& map = scene["entities"][0];
  EXPECT_EQ(map["id"], "map");
  EXPECT_EQ(map["frame_id"], "world");
  EXPECT_EQ(map["timestamp"]["sec"], 1);
  EXPECT_EQ(map["timestamp"]["nsec"], 500000000);
  ASSERT_EQ(map["cubes"].size(), 2u);
  EXPECT_DOUBLE_EQ(map["cubes"][0]["size"]["x"].get<double>(), 0.5);
  MapStyle free_too;
  free_too.show_free = true;
  EXPECT_EQ(mapScene(tree, free_too, 0)["entities"][0]["cubes"].size(), 3u);
  MapStyle unknown_too;
  unknown_too.show_unknown = true;
  // Leaves at x, y in {1.25, 2.25} span 3 x 3 x 1 cells of 0.5 m; 3 known, 6 unknown: with
  // the 2 occupied, 8 cubes (free ones not asked for).
  EXPECT_EQ(mapScene(tree, unknown_too, 0)["entities"][0]["cubes"].size(), 8u);
  MapStyle capped;
  capped.max_cubes = 1;
  bool truncated = false;
  EXPECT_EQ(mapScene(tree, capped, 0, &truncated)["entities"][0]["cubes"].size(), 1u);
  EXPECT_TRUE(truncated);
}

TEST(Scene, PlannerTreeAndPathAreLines) {
  msg::PlannerTree tree;
  tree.nodes({point(0, 0, 0), point(1, 0, 0), point(1, 1, 0)});
  tree.parents({-1, 0, 1});
  const auto t = treeScene(tree)["entities"][0];
  EXPECT_EQ(t["id"], "tree");
  EXPECT_EQ(t["lines"][0]["type"], 2);                                       // line list
  EXPECT_EQ(t["lines"][0]["points"].size(), 3u);                             // each node once
  EXPECT_EQ(t["lines"][0]["indices"], nlohmann::json::array({0, 1, 1, 2}));  // parent, child
  msg::Path path;
  msg::Pose a, b;
  a.position(point(0, 0, 1));
  b.position(point(3, 0, 1));
  path.poses({a, b});
  const auto p = pathScene(path)["entities"][0];
  EXPECT_EQ(p["id"], "path");
  EXPECT_EQ(p["lines"][0]["type"], 0);  // line strip
  EXPECT_EQ(p["lines"][0]["points"][1]["x"], 3.0);
}

TEST(Scene, VehicleTrajectoriesAndTransform) {
  Trajectory estimated(0.5, 3), truth(0.5, 3);
  EXPECT_TRUE(estimated.add(0, 0, 0));
  EXPECT_FALSE(estimated.add(0.1, 0, 0));  // closer than the step
  for (int i = 1; i <= 4; ++i) estimated.add(i, 0, 0);
  EXPECT_EQ(estimated.points().size(), 3u);
  EXPECT_EQ(estimated.points().front().x(), 2.0);  // the oldest went
  const auto scene = vehicleScene(estimated, truth, 0, 1.6, 0.5);
  ASSERT_EQ(scene["entities"].size(), 2u);  // no true trajectory yet
  EXPECT_EQ(scene["entities"][0]["id"], "vehicle");
  EXPECT_EQ(scene["entities"][0]["frame_id"], "vehicle");
  EXPECT_EQ(scene["entities"][1]["id"], "trajectory_estimated");
  msg::Odometry odometry;
  odometry.pose().pose().position(point(1, 2, 3));
  odometry.pose().pose().orientation().w(1);
  const auto tf = vehicleTransform(odometry);
  EXPECT_EQ(tf["parent_frame_id"], "world");
  EXPECT_EQ(tf["child_frame_id"], "vehicle");
  EXPECT_EQ(tf["translation"]["z"], 3.0);
  EXPECT_EQ(tf["rotation"]["w"], 1.0);
  // The display frame: NED north (world x) is map y, east is map x, down is map -z.
  const auto display = displayFrameTransform(0);
  EXPECT_EQ(display["parent_frame_id"], "map");
  EXPECT_EQ(display["child_frame_id"], "world");
  const Eigen::Quaterniond q(
      display["rotation"]["w"].get<double>(), display["rotation"]["x"].get<double>(),
      display["rotation"]["y"].get<double>(), display["rotation"]["z"].get<double>());
  EXPECT_TRUE((q * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((q * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((q * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitZ()));
}

TEST(Scene, CompressedImageAndCameraNames) {
  msg::CompressedImage image;
  image.format("jpeg");
  image.data({'M', 'a', 'n'});
  image.header().frame_id("camera_left");
  const auto json = compressedImage(image);
  EXPECT_EQ(json["data"], "TWFu");
  EXPECT_EQ(json["format"], "jpeg");
  EXPECT_EQ(json["frame_id"], "camera_left");
  const uint8_t two[] = {'M', 'a'};
  EXPECT_EQ(base64(two, 2), "TWE=");
  EXPECT_EQ(base64(two, 1), "TQ==");
  EXPECT_EQ(cameraChannel("/camera/left/compressed"), "/foxglove/camera/left");
  EXPECT_EQ(cameraChannel("cam0"), "/foxglove/camera/cam0");
  for (const char* name : {kSceneUpdate, kFrameTransform, kCompressedImage})
    EXPECT_EQ(nlohmann::json::parse(jsonSchema(name))["title"], name);
}

}  // namespace
}  // namespace auv::foxglove_bridge
