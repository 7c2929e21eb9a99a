#include "auv/sim/camera/calibration_sequence.h"

#include <cmath>
#include <filesystem>
#include <opencv2/core/persistence.hpp>
#include <ostream>
#include <random>
#include <stdexcept>

#include "auv/sim/camera/renderer.h"
#include "auv/sim/camera/video.h"
#include "auv/sim/raycast/ray_caster.h"

namespace auv::sim {
namespace fs = std::filesystem;
namespace {

constexpr double kDeg = M_PI / 180.0;

struct BoardPose {  // board frame -> camera frame
  Eigen::Quaterniond rotation{Eigen::Quaterniond::Identity()};
  Eigen::Vector3d translation{0, 0, 1};
};

BoardPose interpolate(const BoardPose& a, const BoardPose& b, double f) {
  return {a.rotation.slerp(f, b.rotation), (1.0 - f) * a.translation + f * b.translation};
}

// The whole board, border included, lies inside the image (with a margin, since the detector
// needs the white border) and shows its printed face.
bool boardVisible(const CameraModel& camera, const BoardPose& pose, double half_width,
                  double half_height) {
  const Eigen::Vector3d normal_away = pose.rotation * Eigen::Vector3d::UnitZ();
  if (normal_away.dot(pose.translation) <= 0) return false;
  const double margin = 0.02 * camera.width();
  constexpr int kSteps = 8;  // points per edge: distortion bends the edges
  for (int i = 0; i <= kSteps; ++i) {
    const double f = -1.0 + 2.0 * i / kSteps;
    for (const Eigen::Vector3d& corner : {Eigen::Vector3d(f * half_width, -half_height, 0),
                                          Eigen::Vector3d(f * half_width, half_height, 0),
                                          Eigen::Vector3d(-half_width, f * half_height, 0),
                                          Eigen::Vector3d(half_width, f * half_height, 0)}) {
      const auto pixel = camera.project(pose.rotation * corner + pose.translation);
      if (!pixel || pixel->x() < margin || pixel->y() < margin ||
          pixel->x() > camera.width() - 1 - margin || pixel->y() > camera.height() - 1 - margin) {
        return false;
      }
    }
  }
  return true;
}

BoardPose randomBoardPose(std::mt19937_64& rng, const CameraModel& camera,
                          const CalibrationSequenceOptions& options) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double distance =
      options.min_distance + (options.max_distance - options.min_distance) * unit(rng);
  // Aim the board's centre at a random pixel, so the poses cover the whole field of view.
  const int col = std::min(camera.width() - 1, static_cast<int>(unit(rng) * camera.width()));
  const int row = std::min(camera.height() - 1, static_cast<int>(unit(rng) * camera.height()));
  const size_t sample =
      (static_cast<size_t>(row) * camera.width() + col) * camera.samplesPerPixel();
  const Eigen::Vector3d ray = camera.rays()[sample].cast<double>().normalized();
  // Face the camera along that ray, then tilt about a random in-plane axis and spin a little.
  const Eigen::Quaterniond facing =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ray);
  const double axis_angle = 2.0 * M_PI * unit(rng);
  const double tilt = options.max_tilt_deg * kDeg * unit(rng);
  const double spin = (unit(rng) - 0.5) * 30.0 * kDeg;
  BoardPose pose;
  pose.rotation =
      facing *
      Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis_angle), std::sin(axis_angle), 0)) *
      Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ());
  pose.translation = distance * ray;
  return pose;
}

}  // namespace

void CalibrationSequenceOptions::check() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (frames < 1 || frames > 100000) fail("frames: expected 1..100000");
  if (board_columns < 3 || board_rows < 3 || board_columns > 50 || board_rows > 50) {
    fail("board_columns/board_rows: expected 3..50 inner corners");
  }
  if (!(square_size > 0.001 && square_size < 1)) fail("square_size: expected (0.001, 1) m");
  if (!(min_distance > 0.05 && max_distance >= min_distance && max_distance < 100)) {
    fail("min_distance/max_distance: expected 0.05 < min <= max < 100 m");
  }
  if (!(max_tilt_deg >= 0 && max_tilt_deg <= 80)) fail("max_tilt_deg: expected [0, 80] deg");
  if (frames_per_pose < 1) fail("frames_per_pose: expected >= 1");
  if (!(board_depth >= 0 && board_depth < 12000)) fail("board_depth: expected >= 0 m");
  if (!(scale > 0 && scale <= 8)) fail("scale: expected (0, 8]");
  if (supersample < 1 || supersample > 8) fail("supersample: expected 1..8");
}

Mesh makeChessboardMesh(int columns, int rows, double square_size, int texels_per_square) {
  // (columns + 1) x (rows + 1) squares, plus a white border one square wide on every side.
  const int squares_x = columns + 3, squares_y = rows + 3;
  const int t = texels_per_square;
  Mesh mesh;
  mesh.source = "chessboard " + std::to_string(columns) + "x" + std::to_string(rows);
  mesh.texture = cv::Mat(squares_y * t, squares_x * t, CV_8UC3, cv::Scalar::all(235));
  for (int sy = 1; sy < squares_y - 1; ++sy) {
    for (int sx = 1; sx < squares_x - 1; ++sx) {
      if ((sx + sy) % 2 == 0) {
        mesh.texture(cv::Rect(sx * t, sy * t, t, t)).setTo(cv::Scalar::all(20));
      }
    }
  }
  const float hw = static_cast<float>(0.5 * squares_x * square_size);
  const float hh = static_cast<float>(0.5 * squares_y * square_size);
  mesh.vertices = {{-hw, -hh, 0}, {hw, -hh, 0}, {hw, hh, 0}, {-hw, hh, 0}};
  mesh.triangles = {{0, 2, 1}, {0, 3, 2}};  // counter-clockwise seen from -z (the face)
  mesh.triangle_uvs = {{0, 0}, {1, 1}, {1, 0}, {0, 0}, {0, 1}, {1, 1}};
  return mesh;
}

CalibrationSequenceReport renderCalibrationSequence(const CameraOptions& camera_options,
                                                    const WaterOptics& water,
                                                    const IlluminationOptions& illumination,
                                                    const CalibrationSequenceOptions& options,
                                                    const std::string& out_dir) {
  options.check();
  const CameraModel camera(camera_options, options.scale, options.supersample);
  Mesh board = makeChessboardMesh(options.board_columns, options.board_rows, options.square_size);
  const double half_width = 0.5 * (options.board_columns + 3) * options.square_size;
  const double half_height = 0.5 * (options.board_rows + 3) * options.square_size;
  // The board lies face up at board_depth: board x north, y east, z down.
  Eigen::Isometry3d board_to_world = Eigen::Isometry3d::Identity();
  board_to_world.translation() = Eigen::Vector3d(0, 0, options.board_depth);
  transformMesh(board, board_to_world.cast<float>());
  validateMesh(board);
  const RayCaster caster(board);

  // Key poses every frames_per_pose frames; the frames between move smoothly (lerp + slerp).
  // A key pose is redrawn until it and the motion towards it keep the board in view.
  std::mt19937_64 rng(options.seed);
  std::vector<BoardPose> poses;
  BoardPose key;
  int attempts = 0;
  do {
    key = randomBoardPose(rng, camera, options);
    if (++attempts > 10000) throw std::runtime_error("calibration: no board pose fits the view");
  } while (!boardVisible(camera, key, half_width, half_height));
  poses.push_back(key);
  while (static_cast<int>(poses.size()) < options.frames) {
    const BoardPose from = poses.back();
    std::vector<BoardPose> segment;
    for (attempts = 0; segment.empty(); ++attempts) {
      if (attempts > 10000) {
        throw std::runtime_error("calibration: cannot move the board within the field of view");
      }
      const BoardPose next = randomBoardPose(rng, camera, options);
      for (int k = 1; k <= options.frames_per_pose; ++k) {
        segment.push_back(
            interpolate(from, next, static_cast<double>(k) / options.frames_per_pose));
        if (!boardVisible(camera, segment.back(), half_width, half_height)) {
          segment.clear();
          break;
        }
      }
    }
    for (const BoardPose& pose : segment) {
      if (static_cast<int>(poses.size()) < options.frames) poses.push_back(pose);
    }
  }

  fs::create_directories(out_dir);
  CalibrationSequenceReport report;
  report.camera = camera_options.id;
  report.video_path = (fs::path(out_dir) / (camera_options.id + ".mp4")).string();
  report.truth_path = (fs::path(out_dir) / (camera_options.id + "_truth.yaml")).string();
  VideoRecorder recorder(report.video_path, camera_options.frame_rate,
                         cv::Size(camera.width(), camera.height()), options.log);
  for (size_t k = 0; k < poses.size(); ++k) {
    Eigen::Isometry3d board_to_camera = Eigen::Isometry3d::Identity();
    board_to_camera.linear() = poses[k].rotation.toRotationMatrix();
    board_to_camera.translation() = poses[k].translation;
    const Eigen::Isometry3d camera_to_world = board_to_world * board_to_camera.inverse();
    std::vector<SpotLight> lights;
    if (camera_options.lights) {
      SpotLight light;
      light.position = camera_to_world.translation().cast<float>();
      light.direction = camera_to_world.linear().col(2).cast<float>();
      light.intensity = static_cast<float>(camera_options.light_intensity);
      light.beam_deg = static_cast<float>(camera_options.light_beam_deg);
      lights.push_back(light);
    }
    const ImageFormation formation = cameraImageFormation(camera_options, water, illumination,
                                                          lights, camera_to_world.translation());
    const cv::Mat frame = renderFrame(camera, {camera_to_world}, formation, caster,
                                      frameSeed(camera_options.noise_seed, k), options.threads);
    const double sim_time = static_cast<double>(k) / camera_options.frame_rate;
    recorder.write(frame, camera_options.cameraTime(sim_time), sim_time);
    if (options.log && ((k + 1) % 20 == 0 || k + 1 == poses.size())) {
      *options.log << "calibration: " << camera_options.id << ": " << k + 1 << "/" << poses.size()
                   << " frames\n";
    }
  }

  // The truth first under a temporary name; the video is moved into place last.
  const std::string truth_temp = report.truth_path + ".incomplete";
  {
    cv::FileStorage truth(truth_temp, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!truth.isOpened()) throw std::runtime_error(truth_temp + ": cannot write");
    const CameraIntrinsics& k = camera.intrinsics();
    truth << "camera" << camera_options.id;
    truth << "image_width" << k.width << "image_height" << k.height;
    truth << "camera_matrix" << cv::Mat(k.cameraMatrix());
    truth << "distortion_coefficients" << k.distortionCoefficients();
    truth << "board_columns" << options.board_columns << "board_rows" << options.board_rows;
    truth << "square_size" << options.square_size;
    truth << "frames" << static_cast<int>(poses.size());
  }
  recorder.finish();
  fs::rename(truth_temp, report.truth_path);
  report.frames = recorder.frames();
  return report;
}

}  // namespace auv::sim
