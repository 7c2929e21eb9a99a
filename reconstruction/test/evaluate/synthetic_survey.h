#pragma once
// The synthetic survey fixture of the evaluate and figures tests: a seabed with a rock block, a
// simulator-like run folder (25 frames of a down camera "left"), and a survey whose sparse
// model (13 keyframes, points with tracks), dense cloud and mesh are the truth moved by a known
// similarity.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "auv/recon/evaluate/evaluator.h"
#include "auv/recon/evaluate/well_imaged_region.h"
#include "synthetic_scene.h"

namespace auv::recon::evaluate::testing {

class SyntheticSurvey : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = testing::freshFolder(::testing::UnitTest::GetInstance()->current_test_info()->name());
    run_ = root_ / "run";
    survey_ = root_ / "survey";
    // The world: a 12 m seabed at depth 5 and a 1 m rock block standing on it.
    world_ = testing::planeMesh(5.0, 12.0, 24);
    auto rock = open3d::geometry::TriangleMesh::CreateBox(1.0, 1.0, 1.0);
    rock->Translate(Eigen::Vector3d(0.5, 0.8, 4.0));
    world_ += *rock;
    // The true lens (with distortion, as the simulator's) and 25 frames of a down camera 2 m
    // above the seabed, 0.25 m apart along x, swaying 0.3 m sideways.
    scene::Camera lens;
    lens.id = 1;
    lens.model = scene::CameraModel::OPENCV;
    lens.width = 320;
    lens.height = 240;
    lens.fx = lens.fy = 160;
    lens.cx = 159.5;
    lens.cy = 119.5;
    lens.distortion = {0.05, 0.01, 0, 0};
    std::vector<scene::Image> frames;
    for (int f = 0; f < 25; ++f) {
      const Eigen::Vector3d c(-3.0 + 0.25 * f, 0.3 * std::sin(0.5 * f), 3.0);
      frames.push_back(
          testing::downCamera(1000000 + f + 1, 1, c, "left_0001.mp4#" + std::to_string(f)));
    }
    testing::writeRun(run_, world_, lens, frames);

    // The survey: every other frame a keyframe, registered in a frame moved by `sim_`.
    fs::create_directories(survey_ / "keyframes" / "left");
    std::ofstream index(survey_ / "keyframes" / "left" / "index.csv");
    index << "file,video,frame,camera_time_s,sim_time_s,sharpness,motion_px,tracked\n";
    scene::Reconstruction model;
    model.cameras[1] = scene::Camera::pinhole(1, 320, 240, 160, 160, 159.5, 119.5);
    for (int f = 0; f < 25; f += 2) {
      char file[64];
      std::snprintf(file, sizeof(file), "left_0001_%06d.png", f);
      index << file << ",left_0001.mp4," << f << "," << 0.1 * f << ",,100,40,200\n";
      scene::Image image = testing::toReconstruction(frames[f], sim_);
      image.id = static_cast<uint32_t>(f + 1);
      image.name = std::string("left/") + file;
      model.images[image.id] = image;
    }
    index.close();
    // Sparse points: the truth every 10 cm under the cameras, in the model's frame.
    const SurfaceSamples truth_points = sampleSurface(world_, 0.1, 5);
    uint64_t id = 1;
    for (const auto& p : truth_points.points) {
      if (std::abs(p.x()) < 3 && std::abs(p.y()) < 1.5) {
        scene::Point3D point;
        point.id = id++;
        point.xyz = sim_.inverse().apply(p);
        // Observed by the nearest keyframe.
        scene::Image* nearest = nullptr;
        for (auto& [image_id, image] : model.images) {
          if (!nearest ||
              (image.center() - point.xyz).norm() < (nearest->center() - point.xyz).norm()) {
            nearest = &image;
          }
        }
        nearest->points2d.push_back(model.cameras[1].project(nearest->toCamera(point.xyz)));
        nearest->point3d_ids.push_back(static_cast<int64_t>(point.id));
        point.track.push_back({nearest->id, static_cast<uint32_t>(nearest->points2d.size() - 1)});
        model.points[point.id] = point;
      }
    }
    scene::writeColmapText(model, survey_ / "sparse");
    writeDense(0.0);
    // The mesh: the true world in the model's frame.
    scene::PlyData mesh;
    for (const auto& v : world_.vertices_) mesh.positions.push_back(sim_.inverse().apply(v));
    for (const auto& t : world_.triangles_) {
      mesh.triangles.push_back(
          {static_cast<uint32_t>(t(0)), static_cast<uint32_t>(t(1)), static_cast<uint32_t>(t(2))});
    }
    fs::create_directories(survey_ / "mesh");
    scene::writePly(survey_ / "mesh" / "mesh.ply", mesh);
  }

  /// A dense cloud: the truth every 1 cm near the cameras, `shift` m deeper, in the model's
  /// frame.
  void writeDense(double shift) {
    scene::PlyData dense;
    for (const auto& p : sampleSurface(world_, 0.01, 9).points) {
      if (std::abs(p.x()) < 5 && std::abs(p.y()) < 3) {
        dense.positions.push_back(sim_.inverse().apply(p + Eigen::Vector3d(0, 0, shift)));
      }
    }
    fs::create_directories(survey_ / "dense");
    scene::writePly(survey_ / "dense" / "fused.ply", dense);
  }

  static double fscore(const nlohmann::json& result, const std::string& surface, double threshold) {
    for (const auto& t : result["surfaces"][surface]["thresholds"]) {
      if (std::abs(t["threshold_m"].get<double>() - threshold) < 1e-9) return t["fscore"];
    }
    ADD_FAILURE() << "no threshold " << threshold << " for " << surface;
    return -1;
  }

  EvaluateOptions quickOptions() const {
    EvaluateOptions o;
    o.sample_spacing_m = 0.02;
    return o;
  }

  Similarity sim_ = testing::knownSimilarity();
  open3d::geometry::TriangleMesh world_;
  fs::path root_, run_, survey_;
};

}  // namespace auv::recon::evaluate::testing
