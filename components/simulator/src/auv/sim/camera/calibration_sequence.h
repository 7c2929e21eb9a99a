#pragma once
// Underwater calibration sequences (paper section 3.3: the cameras' intrinsics are
// pre-calibrated underwater with a pattern and a standard procedure). A chessboard is moved
// in front of the camera through varied poses (0.8-2 m, tilted up to +-40 deg, all over the
// field of view) in the scenario's water, filmed with the camera's true lens, and written as
//   <out>/<camera>.mp4 (+ .frames.csv)   the video the calibration tool reads
//   <out>/<camera>_truth.yaml            OpenCV FileStorage: image_width, image_height,
//                                        camera_matrix, distortion_coefficients (the truth)

#include <cstdint>
#include <iosfwd>
#include <string>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/world/mesh.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

struct CalibrationSequenceOptions {
  int frames = 60;              ///< frames per camera
  int board_columns = 9;        ///< inner corners along the board's width
  int board_rows = 6;           ///< inner corners along the board's height
  double square_size = 0.06;    ///< m
  double min_distance = 0.8;    ///< m, camera to board centre
  double max_distance = 2.0;    ///< m
  double max_tilt_deg = 40.0;   ///< deg, board tilt away from facing the camera
  int frames_per_pose = 3;      ///< frames of smooth motion from one random board pose to the next
  double board_depth = 4.0;     ///< m, depth of the board (it lies face up, lit by daylight)
  double scale = 1.0;           ///< resolution factor (0, 8]; the truth scales along
  int supersample = 2;          ///< rays per pixel side (anti-aliasing for sub-pixel corners)
  uint64_t seed = 1;            ///< board poses
  int threads = 0;              ///< <= 0 = every core
  std::ostream* log = nullptr;  ///< progress lines, or none

  /// Throws std::invalid_argument naming the field.
  void check() const;
};

struct CalibrationSequenceReport {
  std::string camera;
  std::string video_path;
  std::string truth_path;
  int64_t frames = 0;
};

/// A chessboard with `columns` x `rows` inner corners, black and white squares and a white
/// border one square wide, as one textured quad. Board frame: origin at the centre, x along
/// the width, y along the height, z into the board (the printed face looks along -z); the
/// inner corner (i, j) is at ((i - (columns - 1) / 2) * square, (j - (rows - 1) / 2) * square).
Mesh makeChessboardMesh(int columns, int rows, double square_size, int texels_per_square = 96);

/// Renders the sequence of one camera into `out_dir`. Throws std::runtime_error when no board
/// pose fits the field of view or the video cannot be written.
CalibrationSequenceReport renderCalibrationSequence(const CameraOptions& camera,
                                                    const WaterOptics& water,
                                                    const IlluminationOptions& illumination,
                                                    const CalibrationSequenceOptions& options,
                                                    const std::string& out_dir);

}  // namespace auv::sim
