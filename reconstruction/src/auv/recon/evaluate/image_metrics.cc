#include "auv/recon/evaluate/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

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
  cv::VideoCapture capture(video.string());
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
