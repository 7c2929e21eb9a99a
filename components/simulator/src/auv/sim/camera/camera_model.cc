#include "auv/sim/camera/camera_model.h"

#include <cmath>
#include <opencv2/calib3d.hpp>

namespace auv::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Radial part of OpenCV's distortion: r_distorted = r * (1 + k1 r^2 + k2 r^4 + k3 r^6).
double distortedRadius(const std::array<double, 5>& d, double r) {
  const double r2 = r * r;
  return r * (1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4])));
}

int roundToEven(double value) { return std::max(2, 2 * static_cast<int>(std::lround(value / 2))); }

}  // namespace

cv::Matx33d CameraIntrinsics::cameraMatrix() const {
  return cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1);
}

cv::Mat CameraIntrinsics::distortionCoefficients() const {
  cv::Mat d(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) d.at<double>(i) = distortion[i];
  return d;
}

CameraIntrinsics CameraIntrinsics::scaled(double scale) const {
  CameraIntrinsics out = *this;
  if (scale == 1.0) return out;
  out.width = roundToEven(width * scale);
  out.height = roundToEven(height * scale);
  const double sx = static_cast<double>(out.width) / width;
  const double sy = static_cast<double>(out.height) / height;
  out.fx = fx * sx;
  out.fy = fy * sy;
  // Pixel centres sit at integers, so the image's corner is at -0.5: scale about it.
  out.cx = (cx + 0.5) * sx - 0.5;
  out.cy = (cy + 0.5) * sy - 0.5;
  return out;
}

void CameraOptions::check() const {
  const std::string where = "cameras[" + id + "].";
  auto fail = [&](const std::string& field, const std::string& what) {
    throw ConfigError(where + field + ": " + what);
  };
  if (id.empty()) throw ConfigError("cameras[]: id: must not be empty");
  for (char c : id) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') {
      fail("id", "use letters, digits, '_' or '-' (it names files), got '" + id + "'");
    }
  }
  if (width < 16 || width > 16384) fail("width", "expected 16..16384 px");
  if (height < 16 || height > 16384) fail("height", "expected 16..16384 px");
  if (!(hfov_deg > 1 && hfov_deg < 170)) fail("hfov_deg", "expected (1, 170) deg");
  if (!(fx >= 0) || !std::isfinite(fx))
    fail("fx", "expected a focal length > 0 px (0 = from hfov_deg)");
  if (!(fy >= 0) || !std::isfinite(fy)) fail("fy", "expected a focal length > 0 px (0 = fx)");
  if (!std::isfinite(cx) || cx >= width) fail("cx", "must lie inside the image (< width)");
  if (!std::isfinite(cy) || cy >= height) fail("cy", "must lie inside the image (< height)");
  for (double d : distortion) {
    if (!std::isfinite(d) || std::abs(d) > 10)
      fail("distortion", "coefficients must be finite, |k| <= 10");
  }
  if (!(frame_rate > 0 && frame_rate <= 1000)) fail("frame_rate", "expected (0, 1000] Hz");
  if (!position.allFinite()) fail("position", "must be finite (m, body FRD)");
  const std::pair<const char*, double> angles[] = {
      {"roll_deg", roll_deg}, {"pitch_deg", pitch_deg}, {"yaw_deg", yaw_deg}};
  for (const auto& [name, value] : angles) {
    if (!std::isfinite(value) || std::abs(value) > 360) fail(name, "expected [-360, 360] deg");
  }
  if (!std::isfinite(clock_offset)) fail("clock_offset", "must be finite (s)");
  if (!(std::abs(clock_drift_ppm) <= 1e4)) fail("clock_drift_ppm", "expected |drift| <= 10000 ppm");
  if (!(exposure > 0 && exposure <= 1e3)) fail("exposure", "expected a gain in (0, 1000]");
  if (!(exposure_time >= 0 && exposure_time <= 1)) fail("exposure_time", "expected [0, 1] s");
  if (max_blur_samples < 1 || max_blur_samples > 64) fail("max_blur_samples", "expected 1..64");
  if (!(noise_sigma >= 0 && noise_sigma <= 0.5)) fail("noise_sigma", "expected [0, 0.5]");
  if (!(vignetting >= 0 && vignetting <= 1)) fail("vignetting", "expected [0, 1]");
  if (!(light_intensity >= 0 && light_intensity <= 1e4))
    fail("light_intensity", "expected [0, 1e4]");
  if (!(light_beam_deg > 1 && light_beam_deg < 180))
    fail("light_beam_deg", "expected (1, 180) deg");

  // The lens must not fold: the radial distortion has to increase monotonically out to the
  // image corners, or a pixel would see two directions and undistortion would be ambiguous.
  const CameraIntrinsics k = intrinsics();
  if (!(k.fx > 0 && std::isfinite(k.fx))) {
    fail("hfov_deg", "with this distortion no focal length spans the field of view");
  }
  double corner_radius = 0;
  for (double u : {-0.5, width - 0.5}) {
    for (double v : {-0.5, height - 0.5}) {
      corner_radius = std::max(corner_radius, std::hypot((u - k.cx) / k.fx, (v - k.cy) / k.fy));
    }
  }
  double previous = 0;
  for (double r = 1e-3;; r += 1e-3) {
    const double rd = distortedRadius(distortion, r);
    if (rd <= previous) {
      fail("distortion",
           "the lens folds before the image corners (radial distortion must "
           "increase out to them); reduce the negative coefficients");
    }
    if (rd > corner_radius * 1.02) break;
    if (r > 50) fail("distortion", "the image corners are beyond a 177 deg field of view");
    previous = rd;
  }
}

CameraOptions CameraOptions::defaults(const std::string& id) {
  CameraOptions o;
  o.id = id;
  // Sparus II payload: two cameras looking down, tilted 20 deg to port and starboard, and one
  // looking forward and 40 deg down (paper section 4.1). Each GoPro runs on its own clock.
  if (id == "left") {
    o.position = {0.45, -0.08, 0.12};
    o.pitch_deg = -90.0;
    o.roll_deg = 20.0;
    o.clock_offset = 37.412;
    o.clock_drift_ppm = 23.0;
    o.noise_seed = 11;
  } else if (id == "right") {
    o.position = {0.45, 0.08, 0.12};
    o.pitch_deg = -90.0;
    o.roll_deg = -20.0;
    o.clock_offset = -12.871;
    o.clock_drift_ppm = -31.0;
    o.noise_seed = 12;
  } else if (id == "forward") {
    o.position = {0.62, 0.0, 0.05};
    o.pitch_deg = -40.0;
    o.clock_offset = 5.236;
    o.clock_drift_ppm = 17.0;
    o.noise_seed = 13;
  } else {
    // Another camera gets its own (reproducible) clock error from its name (FNV-1a hash).
    uint64_t hash = 1469598103934665603ull;
    for (char c : id) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    o.clock_offset = static_cast<double>(hash % 60000) / 1000.0 - 30.0;
    o.clock_drift_ppm = static_cast<double>((hash / 60000) % 101) - 50.0;
    o.noise_seed = hash;
  }
  return o;
}

CameraOptions CameraOptions::fromYaml(const YamlSection& s) {
  s.rejectUnknownKeys({"id",
                       "width",
                       "height",
                       "hfov_deg",
                       "fx",
                       "fy",
                       "cx",
                       "cy",
                       "distortion",
                       "frame_rate",
                       "position",
                       "roll_deg",
                       "pitch_deg",
                       "yaw_deg",
                       "synchronized",
                       "clock_offset",
                       "clock_drift_ppm",
                       "auto_exposure",
                       "exposure",
                       "exposure_time",
                       "max_blur_samples",
                       "noise_sigma",
                       "vignetting",
                       "noise_seed",
                       "lights",
                       "light_intensity",
                       "light_beam_deg"});
  if (!s.has("id")) s.fail("id", "missing: the camera's name (e.g. left, right, forward)");
  std::string id;
  s.read("id", id);
  CameraOptions o = defaults(id);
  s.read("width", o.width, 16, 16384);
  s.read("height", o.height, 16, 16384);
  s.read("hfov_deg", o.hfov_deg, 1.0, 170.0);
  if (s.has("fx") && s.has("hfov_deg")) s.fail("fx", "give either fx or hfov_deg, not both");
  s.read("fx", o.fx, 1.0, 1e6);
  s.read("fy", o.fy, 1.0, 1e6);
  if (s.has("fy") && !s.has("fx")) s.fail("fy", "needs fx too");
  s.read("cx", o.cx, -0.5, 16384.0);
  s.read("cy", o.cy, -0.5, 16384.0);
  if (s.has("cx") && o.cx >= o.width) s.fail("cx", "must lie inside the image (< width)");
  if (s.has("cy") && o.cy >= o.height) s.fail("cy", "must lie inside the image (< height)");
  if (s.has("distortion")) {
    std::vector<double> d;
    s.read("distortion", d);
    if (d.size() != 4 && d.size() != 5) {
      s.fail("distortion", "expected [k1, k2, p1, p2] or [k1, k2, p1, p2, k3] (OpenCV), got " +
                               std::to_string(d.size()) + " numbers");
    }
    o.distortion = {d[0], d[1], d[2], d[3], d.size() == 5 ? d[4] : 0.0};
  }
  s.read("frame_rate", o.frame_rate, 0.01, 1000.0);
  s.read("position", o.position, -100.0, 100.0);
  s.read("roll_deg", o.roll_deg, -360.0, 360.0);
  s.read("pitch_deg", o.pitch_deg, -360.0, 360.0);
  s.read("yaw_deg", o.yaw_deg, -360.0, 360.0);
  s.read("synchronized", o.synchronized);
  s.read("clock_offset", o.clock_offset, -1e9, 1e9);
  s.read("clock_drift_ppm", o.clock_drift_ppm, -1e4, 1e4);
  s.read("auto_exposure", o.auto_exposure);
  s.read("exposure", o.exposure, 1e-3, 1e3);
  s.read("exposure_time", o.exposure_time, 0.0, 1.0);
  s.read("max_blur_samples", o.max_blur_samples, 1, 64);
  s.read("noise_sigma", o.noise_sigma, 0.0, 0.5);
  s.read("vignetting", o.vignetting, 0.0, 1.0);
  if (s.has("noise_seed")) {
    int seed = 0;
    s.read("noise_seed", seed, 0);
    o.noise_seed = static_cast<uint64_t>(seed);
  }
  s.read("lights", o.lights);
  s.read("light_intensity", o.light_intensity, 0.0, 1e4);
  s.read("light_beam_deg", o.light_beam_deg, 1.0, 179.0);
  try {
    o.check();
  } catch (const ConfigError& e) {
    throw ConfigError(s.file() + ": " + s.path() + ": " + e.what());
  }
  return o;
}

CameraIntrinsics CameraOptions::intrinsics(double scale) const {
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.distortion = distortion;
  if (fx > 0) {
    k.fx = fx;
  } else {
    // The edge of the middle row (x = width / 2 px from the centre) sees the ray at
    // hfov / 2: its distorted normalised coordinate is x_d = t (1 + k1 t^2 + ...) + 3 p2 t^2.
    const double t = std::tan(0.5 * hfov_deg * kDeg);
    const double x_d = distortedRadius(distortion, t) + 3.0 * distortion[3] * t * t;
    k.fx = x_d > 0 ? 0.5 * width / x_d : std::numeric_limits<double>::quiet_NaN();
  }
  k.fy = fy > 0 ? fy : k.fx;
  k.cx = cx >= 0 ? cx : 0.5 * (width - 1);
  k.cy = cy >= 0 ? cy : 0.5 * (height - 1);
  return k.scaled(scale);
}

Eigen::Isometry3d CameraOptions::cameraToBody() const {
  Eigen::Matrix3d aligned;  // columns: camera x, y, z axes in the body frame
  aligned.col(0) = Eigen::Vector3d::UnitY();
  aligned.col(1) = Eigen::Vector3d::UnitZ();
  aligned.col(2) = Eigen::Vector3d::UnitX();
  const Eigen::Matrix3d mount = (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()))
                                    .toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = mount * aligned;
  T.translation() = position;
  return T;
}

double CameraOptions::cameraTime(double sim_time) const {
  if (synchronized) return sim_time;
  return clock_offset + (1.0 + clock_drift_ppm * 1e-6) * sim_time;
}

double CameraOptions::simTime(double camera_time) const {
  if (synchronized) return camera_time;
  return (camera_time - clock_offset) / (1.0 + clock_drift_ppm * 1e-6);
}

CameraModel::CameraModel(const CameraOptions& options, double scale, int supersample)
    : options_(options), intrinsics_(options.intrinsics(scale)), supersample_(supersample) {
  options_.check();
  if (!(scale > 0 && scale <= 8))
    throw ConfigError("camera scale: expected (0, 8], got " + std::to_string(scale));
  if (supersample < 1 || supersample > 8) throw ConfigError("camera supersample: expected 1..8");
  const int w = intrinsics_.width, h = intrinsics_.height, spp = samplesPerPixel();

  // Sub-pixel sample k of a pixel sits at offset (k + 0.5) / s - 0.5 from its centre.
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<size_t>(w) * h * spp);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      for (int sy = 0; sy < supersample_; ++sy) {
        for (int sx = 0; sx < supersample_; ++sx) {
          pixels.emplace_back(col + (sx + 0.5f) / supersample_ - 0.5f,
                              row + (sy + 0.5f) / supersample_ - 0.5f);
        }
      }
    }
  }
  // Iterate to convergence: the default 5 iterations leave ~0.1 px at wide-angle corners.
  std::vector<cv::Point2f> normalised;
  cv::undistortPoints(pixels, normalised, intrinsics_.cameraMatrix(),
                      intrinsics_.distortionCoefficients(), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-9));
  rays_.resize(normalised.size());
  for (size_t i = 0; i < normalised.size(); ++i) {
    rays_[i] = Eigen::Vector3f(normalised[i].x, normalised[i].y, 1.0f).normalized();
  }
  cos_off_axis_.create(h, w, CV_32F);
  for (int row = 0; row < h; ++row) {
    float* out = cos_off_axis_.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      Eigen::Vector3f mean = Eigen::Vector3f::Zero();
      const size_t base = (static_cast<size_t>(row) * w + col) * spp;
      for (int s = 0; s < spp; ++s) mean += rays_[base + s];
      out[col] = mean.normalized().z();
    }
  }
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p) const {
  if (!(p.z() > 1e-9)) return std::nullopt;
  const auto& d = intrinsics_.distortion;
  const double x = p.x() / p.z(), y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
  const double xd = x * radial + 2.0 * d[2] * x * y + d[3] * (r2 + 2.0 * x * x);
  const double yd = y * radial + d[2] * (r2 + 2.0 * y * y) + 2.0 * d[3] * x * y;
  return Eigen::Vector2d(intrinsics_.fx * xd + intrinsics_.cx,
                         intrinsics_.fy * yd + intrinsics_.cy);
}

}  // namespace auv::sim
