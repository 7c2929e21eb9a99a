#pragma once
// One camera of the vehicle (paper section 4.1: GoPro Hero 4 cameras in flat-port housings):
// its options as a scenario file gives them (intrinsics, lens distortion, mounting, clock,
// sensor, lights) and the geometric model built from them (a cached unit ray per pixel with
// the distortion applied, and the projection of points).
//
// Frames. The camera frame is OpenCV's: x right, y down, z along the optical axis. Pixel
// centres are at integer coordinates (OpenCV); COLMAP's convention (+0.5) is applied only
// when writing COLMAP files. A "body-aligned" camera looks along body x (forward) with image x
// along body y (starboard) and image y along body z (down). The mounting orientation rotates
// that camera about the BODY axes, in this order:
//   1. pitch about body y: negative tilts the view down (-90 = straight down, image top forward);
//   2. roll about body x (right-hand rule): positive turns a down-looking view to port;
//   3. yaw about body z: positive turns the view to starboard.
// So R_body_camera = Rz(yaw) * Rx(roll) * Ry(pitch) * R_aligned. Pitch goes first so that a
// down-looking camera can still be tilted sideways (with yaw-pitch-roll order, roll at
// pitch -90 would only spin the image).
//
// Clock. A camera is a stand-alone recorder with its own clock:
//   camera_time = clock_offset + (1 + clock_drift_ppm * 1e-6) * sim_time,
// frames are evenly spaced in camera time. `synchronized: true` forces offset = drift = 0.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "auv/sim/common/yaml_section.h"

namespace auv::sim {

/// Resolved pinhole + OpenCV distortion parameters of one image size.
struct CameraIntrinsics {
  int width = 0;                       ///< px
  int height = 0;                      ///< px
  double fx = 0, fy = 0;               ///< px
  double cx = 0, cy = 0;               ///< px, OpenCV convention (pixel centres at integers)
  std::array<double, 5> distortion{};  ///< OpenCV k1 k2 p1 p2 k3

  cv::Matx33d cameraMatrix() const;
  cv::Mat distortionCoefficients() const;  ///< 1x5 CV_64F
  /// The same lens at another resolution (width/height rounded to even numbers, which H.264
  /// needs; the principal point scales about the image's corner, not the first pixel centre).
  CameraIntrinsics scaled(double scale) const;
};

/// One camera as the scenario's `cameras:` list describes it. Every field has a default; a
/// list element starts from the default rig's camera with the same id, if there is one.
struct CameraOptions {
  std::string id = "camera";  ///< name of the camera, its video folder and files
  int width = 960;            ///< px (GoPro-like 4:3; 2704 x 2028 is the real sensor mode)
  int height = 720;           ///< px
  /// deg, horizontal field of view spanned by the image's middle row, distortion included
  /// (flat-port GoPro underwater: ~80-90 deg). Used when fx is not given.
  double hfov_deg = 85.0;
  double fx = 0;   ///< px, focal length; 0 = derive from hfov_deg
  double fy = 0;   ///< px; 0 = fx (square pixels)
  double cx = -1;  ///< px, principal point; < 0 = image centre ((width - 1) / 2)
  double cy = -1;  ///< px; < 0 = image centre
  /// OpenCV k1 k2 p1 p2 k3. A flat port magnifies towards the edges: mild pin-cushion (k1 > 0).
  std::array<double, 5> distortion{0.08, 0.02, 0.0, 0.0, 0.0};
  double frame_rate = 10.0;  ///< Hz, in camera time

  Eigen::Vector3d position{0.5, 0.0, 0.1};  ///< m, optical centre in the body frame (FRD)
  double roll_deg = 0.0;   ///< deg, about body x after pitch (see the file comment)
  double pitch_deg = 0.0;  ///< deg, about body y, negative = looking down
  double yaw_deg = 0.0;    ///< deg, about body z, positive = looking to starboard

  bool synchronized = false;     ///< true: camera clock = simulation clock
  double clock_offset = 0.0;     ///< s, camera clock reading at sim time 0
  double clock_drift_ppm = 0.0;  ///< ppm, rate error of the camera clock

  /// Auto exposure (GoPro-like): irradiance is measured relative to the daylight (plus lights)
  /// at the camera's depth, so images keep their brightness as the vehicle dives; false =
  /// absolute units (surface daylight = 1).
  bool auto_exposure = true;
  double exposure = 1.0;         ///< gain applied to the linear radiance before encoding
  double exposure_time = 0.008;  ///< s, shutter time (motion blur); 0 = instantaneous
  int max_blur_samples = 6;      ///< sub-exposure renders per frame at most (1 = no blur)
  double noise_sigma = 0.004;    ///< sensor noise std, fraction of full scale (x255 for 8 bit)
  double vignetting = 0.35;      ///< 0..1: blend from flat (0) to cos^4 fall-off (1)
  uint64_t noise_seed = 1;       ///< seed of the sensor noise (mixed with the frame index)

  bool lights = false;            ///< an artificial light beside the camera, along its axis
  double light_intensity = 2.0;   ///< irradiance (linear, white) at 1 m on the beam axis, in air
  double light_beam_deg = 100.0;  ///< deg, full cone angle of the beam (soft 10 deg edge)

  /// The default rig's camera with this id ("left", "right", "forward"), or generic defaults
  /// (looking forward, with a clock error derived from the name) for any other id.
  static CameraOptions defaults(const std::string& id);
  /// Throws ConfigError naming `cameras[<id>].<field>` for an unusable value.
  void check() const;
  /// Reads one element of the scenario's `cameras:` list strictly (unknown keys rejected),
  /// starting from defaults(id); `id` is required.
  /// Keys: id, width, height, hfov_deg, fx, fy, cx, cy, distortion ([k1, k2, p1, p2, k3]),
  /// frame_rate, position, roll_deg, pitch_deg, yaw_deg, synchronized, clock_offset,
  /// clock_drift_ppm, auto_exposure, exposure, exposure_time, max_blur_samples, noise_sigma,
  /// vignetting, noise_seed, lights, light_intensity, light_beam_deg.
  static CameraOptions fromYaml(const YamlSection& section);

  /// Intrinsics at the configured size times `scale` (fx from hfov_deg when not given).
  CameraIntrinsics intrinsics(double scale = 1.0) const;
  /// Camera frame (OpenCV) -> body frame (FRD).
  Eigen::Isometry3d cameraToBody() const;
  /// Reading of the camera's clock at a simulation time, and back.
  double cameraTime(double sim_time) const;
  double simTime(double camera_time) const;
};

/// The geometric model of a camera at one resolution. Immutable, thread-safe to share.
class CameraModel {
 public:
  /// Caches `supersample`^2 unit rays per pixel (regular sub-pixel grid), undistorting every
  /// sample's pixel coordinates once with cv::undistortPoints.
  explicit CameraModel(const CameraOptions& options, double scale = 1.0, int supersample = 1);

  const CameraOptions& options() const { return options_; }
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }
  int samplesPerPixel() const { return supersample_ * supersample_; }
  /// Unit rays in the camera frame; sample s of pixel (row, col) is at
  /// ((row * width + col) * samplesPerPixel() + s).
  const std::vector<Eigen::Vector3f>& rays() const { return rays_; }
  /// Per pixel (CV_32F): cosine of the angle between the pixel's ray and the optical axis.
  const cv::Mat& cosOffAxis() const { return cos_off_axis_; }

  /// Pixel (OpenCV convention) of a point in the camera frame, distortion included, as
  /// cv::projectPoints computes it; nullopt when the point is not in front of the camera.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& point_camera) const;

 private:
  CameraOptions options_;
  CameraIntrinsics intrinsics_;
  int supersample_ = 1;
  std::vector<Eigen::Vector3f> rays_;
  cv::Mat cos_off_axis_;
};

}  // namespace auv::sim
