#include "auv/recon/evaluate/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::evaluate {
namespace {

double psnrFromMse(double mse) {
  return mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
}

}  // namespace

PsnrResult psnr(const cv::Mat& reference, const cv::Mat& test, const cv::Mat& mask) {
  if (reference.empty() || reference.size() != test.size() || reference.type() != test.type()) {
    throw std::invalid_argument("psnr: the images differ in size or type (or are empty)");
  }
  if (reference.depth() != CV_8U) throw std::invalid_argument("psnr: 8-bit images expected");
  if (!mask.empty() && (mask.size() != reference.size() || mask.type() != CV_8U)) {
    throw std::invalid_argument("psnr: the mask must be CV_8U of the images' size");
  }
  const int channels = reference.channels();
  // Per channel sums for the error and for the least-squares gain/offset fit
  // test' = a * test + b against the reference.
  std::vector<double> n(channels, 0), sx(channels, 0), sy(channels, 0), sxx(channels, 0),
      sxy(channels, 0), syy(channels, 0);
  PsnrResult result;
  for (int r = 0; r < reference.rows; ++r) {
    const uint8_t* ref = reference.ptr<uint8_t>(r);
    const uint8_t* tst = test.ptr<uint8_t>(r);
    const uint8_t* m = mask.empty() ? nullptr : mask.ptr<uint8_t>(r);
    for (int c = 0; c < reference.cols; ++c) {
      if (m && !m[c]) continue;
      ++result.pixels;
      for (int k = 0; k < channels; ++k) {
        const double y = ref[c * channels + k], x = tst[c * channels + k];
        n[k] += 1;
        sx[k] += x;
        sy[k] += y;
        sxx[k] += x * x;
        sxy[k] += x * y;
        syy[k] += y * y;
      }
    }
  }
  if (result.pixels == 0) return result;
  double sse = 0, sse_gain = 0, count = 0;
  for (int k = 0; k < channels; ++k) {
    // sum (y - x)^2 = syy - 2 sxy + sxx
    sse += syy[k] - 2 * sxy[k] + sxx[k];
    const double var_x = sxx[k] - sx[k] * sx[k] / n[k];
    const double cov = sxy[k] - sx[k] * sy[k] / n[k];
    const double var_y = syy[k] - sy[k] * sy[k] / n[k];
    // Residual of the least-squares line: var_y - cov^2 / var_x (all of var_y for a flat test).
    sse_gain += var_x > 1e-9 ? var_y - cov * cov / var_x : var_y;
    count += n[k];
  }
  result.mse = std::max(0.0, sse) / count;
  result.psnr_db = psnrFromMse(result.mse);
  result.psnr_gain_db = psnrFromMse(std::max(0.0, sse_gain) / count);
  return result;
}

std::vector<cv::Mat> readVideoFrames(const std::filesystem::path& video,
                                     const std::vector<int64_t>& frames) {
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  if (!capture.isOpened()) throw StageError("evaluate", video.string() + ": cannot open video");
  std::map<int64_t, size_t> wanted;
  for (size_t i = 0; i < frames.size(); ++i) wanted.emplace(frames[i], i);
  std::vector<cv::Mat> out(frames.size());
  int64_t index = 0;
  cv::Mat image;
  for (auto it = wanted.begin(); it != wanted.end();) {
    if (!capture.read(image)) {
      throw StageError("evaluate", video.string() + ": has " + std::to_string(index) +
                                       " frames, frame " + std::to_string(it->first) +
                                       " was asked for");
    }
    while (it != wanted.end() && it->first == index) {
      out[it->second] = image.clone();
      ++it;
    }
    ++index;
  }
  // Duplicates in `frames` share one decoded image.
  for (size_t i = 0; i < frames.size(); ++i) {
    if (out[i].empty()) out[i] = out[wanted[frames[i]]];
  }
  return out;
}

double ciede2000(const cv::Vec3d& lab1, const cv::Vec3d& lab2) {
  constexpr double kDeg = M_PI / 180.0, k25pow7 = 6103515625.0;  // 25^7
  const double L1 = lab1[0], a1 = lab1[1], b1 = lab1[2], L2 = lab2[0], a2 = lab2[1], b2 = lab2[2];
  const double c_mean = 0.5 * (std::hypot(a1, b1) + std::hypot(a2, b2));
  const double c7 = std::pow(c_mean, 7);
  const double g = 0.5 * (1 - std::sqrt(c7 / (c7 + k25pow7)));
  const double a1p = (1 + g) * a1, a2p = (1 + g) * a2;
  const double c1p = std::hypot(a1p, b1), c2p = std::hypot(a2p, b2);
  const auto hue = [](double b, double a) {
    if (a == 0 && b == 0) return 0.0;
    const double h = std::atan2(b, a) / (M_PI / 180.0);
    return h < 0 ? h + 360 : h;
  };
  const double h1p = hue(b1, a1p), h2p = hue(b2, a2p);
  const double dl = L2 - L1, dc = c2p - c1p;
  double dh = 0;
  if (c1p * c2p != 0) {
    dh = h2p - h1p;
    if (dh > 180) dh -= 360;
    if (dh < -180) dh += 360;
  }
  const double dH = 2 * std::sqrt(c1p * c2p) * std::sin(0.5 * dh * kDeg);
  const double l_mean = 0.5 * (L1 + L2), cp_mean = 0.5 * (c1p + c2p);
  double h_mean = h1p + h2p;
  if (c1p * c2p != 0) {
    if (std::abs(h1p - h2p) <= 180) {
      h_mean = 0.5 * (h1p + h2p);
    } else {
      h_mean = h1p + h2p < 360 ? 0.5 * (h1p + h2p + 360) : 0.5 * (h1p + h2p - 360);
    }
  }
  const double t = 1 - 0.17 * std::cos((h_mean - 30) * kDeg) + 0.24 * std::cos(2 * h_mean * kDeg) +
                   0.32 * std::cos((3 * h_mean + 6) * kDeg) -
                   0.20 * std::cos((4 * h_mean - 63) * kDeg);
  const double d_theta = 30 * std::exp(-std::pow((h_mean - 275) / 25, 2));
  const double cp7 = std::pow(cp_mean, 7);
  const double rc = 2 * std::sqrt(cp7 / (cp7 + k25pow7));
  const double l50 = (l_mean - 50) * (l_mean - 50);
  const double sl = 1 + 0.015 * l50 / std::sqrt(20 + l50);
  const double sc = 1 + 0.045 * cp_mean, sh = 1 + 0.015 * cp_mean * t;
  const double rt = -std::sin(2 * d_theta * kDeg) * rc;
  const double x = dl / sl, y = dc / sc, z = dH / sh;
  return std::sqrt(std::max(0.0, x * x + y * y + z * z + rt * y * z));
}

DeltaEResult deltaE2000(const cv::Mat& reference, const cv::Mat& test, const cv::Mat& mask) {
  if (reference.empty() || reference.size() != test.size() || reference.type() != CV_8UC3 ||
      test.type() != CV_8UC3) {
    throw std::invalid_argument("deltaE2000: two 8-bit BGR images of one size expected");
  }
  if (!mask.empty() && (mask.size() != reference.size() || mask.type() != CV_8U)) {
    throw std::invalid_argument("deltaE2000: the mask must be CV_8U of the images' size");
  }
  cv::Mat lab_ref, lab_test, f;
  reference.convertTo(f, CV_32F, 1.0 / 255);
  cv::cvtColor(f, lab_ref, cv::COLOR_BGR2Lab);  // sRGB decoding included, L in [0, 100]
  test.convertTo(f, CV_32F, 1.0 / 255);
  cv::cvtColor(f, lab_test, cv::COLOR_BGR2Lab);
  std::vector<double> values;
  for (int r = 0; r < reference.rows; ++r) {
    for (int c = 0; c < reference.cols; ++c) {
      if (!mask.empty() && !mask.at<uint8_t>(r, c)) continue;
      values.push_back(ciede2000(lab_ref.at<cv::Vec3f>(r, c), lab_test.at<cv::Vec3f>(r, c)));
    }
  }
  DeltaEResult result;
  result.pixels = values.size();
  if (values.empty()) return result;
  double sum = 0;
  for (double v : values) sum += v;
  result.mean = sum / values.size();
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  result.median = values[values.size() / 2];
  return result;
}

cv::Mat readVideoFrame(const std::filesystem::path& video, int64_t frame) {
  return readVideoFrames(video, {frame}).front();
}

std::vector<int64_t> heldOutFrames(std::vector<int64_t> keyframes, int64_t frame_count,
                                   size_t count) {
  std::sort(keyframes.begin(), keyframes.end());
  keyframes.erase(std::unique(keyframes.begin(), keyframes.end()), keyframes.end());
  // Gaps between consecutive keyframes, widest first.
  std::vector<std::pair<int64_t, int64_t>> gaps;  // (width, middle frame)
  for (size_t i = 0; i + 1 < keyframes.size(); ++i) {
    const int64_t width = keyframes[i + 1] - keyframes[i];
    if (width >= 2) gaps.push_back({width, keyframes[i] + width / 2});
  }
  std::sort(gaps.begin(), gaps.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::vector<int64_t> held;
  for (const auto& [width, middle] : gaps) {
    if (held.size() >= count) break;
    if (middle >= 0 && middle < frame_count) held.push_back(middle);
  }
  std::sort(held.begin(), held.end());
  return held;
}

}  // namespace auv::recon::evaluate
