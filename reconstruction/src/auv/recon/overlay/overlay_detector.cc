#include "auv/recon/overlay/overlay_detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/keyframes/video.h"

namespace fs = std::filesystem;

namespace auv::recon::overlay {

void OverlayOptions::check() const {
  AUV_RECON_CHECK_OPTION(samples >= 2 && samples <= 10000, samples, "must be in [2, 10000]");
  AUV_RECON_CHECK_OPTION(max_std > 0 && max_std < 128, max_std, "must be in (0, 128) grey levels");
  AUV_RECON_CHECK_OPTION(min_gradient > 0, min_gradient, "must be > 0 grey levels per px");
  AUV_RECON_CHECK_OPTION(max_std_flat >= 0 && max_std_flat < max_std, max_std_flat,
                         "must be in [0, max_std) grey levels");
  AUV_RECON_CHECK_OPTION(close_px >= 0 && close_px <= 255, close_px, "must be in [0, 255] px");
  AUV_RECON_CHECK_OPTION(min_area_px >= 0, min_area_px, "must be >= 0 px");
  AUV_RECON_CHECK_OPTION(dilate_px >= 0 && dilate_px <= 255, dilate_px, "must be in [0, 255] px");
  AUV_RECON_CHECK_OPTION(min_moving_fraction >= 0 && min_moving_fraction <= 1, min_moving_fraction,
                         "must be in [0, 1]");
}

OverlayDetector::OverlayDetector(const OverlayOptions& options) : options_(options) {
  options_.check();
}

void OverlayDetector::add(const cv::Mat& frame) {
  if (frame.empty() || frame.depth() != CV_8U) {
    throw std::invalid_argument("overlay: not an 8-bit frame");
  }
  cv::Mat grey;
  if (frame.channels() == 1) {
    grey = frame;
  } else {
    cv::cvtColor(frame, grey, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  }
  if (frames_ > 0 && grey.size() != mean_.size()) {
    throw std::invalid_argument("overlay: frame of " + std::to_string(grey.cols) + "x" +
                                std::to_string(grey.rows) + " px among frames of " +
                                std::to_string(mean_.cols) + "x" + std::to_string(mean_.rows));
  }
  cv::Mat x;
  grey.convertTo(x, CV_64F);
  if (frames_ == 0) {
    mean_ = cv::Mat::zeros(x.size(), CV_64F);
    m2_ = cv::Mat::zeros(x.size(), CV_64F);
  }
  ++frames_;
  // Welford: numerically stable over many frames.
  const cv::Mat delta = x - mean_;
  mean_ += delta / frames_;
  m2_ += delta.mul(x - mean_);
}

OverlayDetection OverlayDetector::detect() const {
  if (frames_ < 2) {
    throw std::runtime_error("overlay: " + std::to_string(frames_) +
                             " frame(s) read; at least 2 are needed");
  }
  OverlayDetection out;
  out.frames = frames_;
  cv::Mat std_dev;
  cv::sqrt(m2_ / (frames_ - 1), std_dev);
  const double pixels = static_cast<double>(std_dev.total());
  out.moving_fraction = cv::countNonZero(std_dev > 2 * options_.max_std) / pixels;
  if (out.moving_fraction < options_.min_moving_fraction) {
    throw std::runtime_error(
        "overlay: the scene barely moves over the " + std::to_string(frames_) +
        " frames sampled (" + std::to_string(100 * out.moving_fraction) +
        " % of the pixels vary by more than 2 x max_std, min_moving_fraction " +
        std::to_string(100 * options_.min_moving_fraction) +
        " %): a still scene cannot be told from an overlay; draw the mask by hand");
  }
  // The moving scene blurs out of the mean; the overlay's edges stay sharp in it.
  cv::Mat gx, gy, gradient;
  cv::Sobel(mean_, gx, CV_64F, 1, 0, 3, 0.25);
  cv::Sobel(mean_, gy, CV_64F, 0, 1, 3, 0.25);
  cv::magnitude(gx, gy, gradient);
  const cv::Mat still = std_dev < options_.max_std;
  // Flat seeds count only in solid patches: a scene's pixels that happen to barely vary are
  // scattered, and the closing below would join them into blobs.
  cv::Mat flat = std_dev < options_.max_std_flat;
  cv::morphologyEx(flat, flat, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  cv::Mat seeds = (still & (gradient > options_.min_gradient)) | flat;
  // A part of the vehicle in a corner has no edge along the image border: still border pixels
  // close its outline (a still stretch of scene along the border stays a thin line, removed by
  // the opening below).
  cv::Mat frame = cv::Mat::zeros(seeds.size(), CV_8U);
  // Two pixels wide: cv::findContours ignores the outermost one.
  cv::rectangle(frame, cv::Rect(0, 0, frame.cols, frame.rows), cv::Scalar(255), 1);
  cv::rectangle(frame, cv::Rect(1, 1, frame.cols - 2, frame.rows - 2), cv::Scalar(255), 1);
  seeds |= still & frame;
  // Seeds along an anti-aliased slanted edge are every other pixel: a closing alone does not
  // join them (a disk slips between), a 2 px dilation does; it is taken back after the fill.
  const cv::Mat join = cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5});
  cv::dilate(seeds, seeds, join);
  if (options_.close_px > 0) {
    const cv::Mat kernel = cv::getStructuringElement(
        cv::MORPH_ELLIPSE, {2 * options_.close_px + 1, 2 * options_.close_px + 1});
    // On a zero margin: nothing outside the image joins a blob to the border.
    const int m = options_.close_px + 1;
    cv::Mat padded;
    cv::copyMakeBorder(seeds, padded, m, m, m, m, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::morphologyEx(padded, padded, cv::MORPH_CLOSE, kernel);
    seeds = padded(cv::Rect(m, m, seeds.cols, seeds.rows)).clone();
  }
  // Fill holes (the inside of a read-out box, changing digits) and drop small blobs.
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(seeds, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat overlay = cv::Mat::zeros(seeds.size(), CV_8U);
  for (size_t i = 0; i < contours.size(); ++i) {
    if (cv::contourArea(contours[i]) < options_.min_area_px) continue;
    cv::drawContours(overlay, contours, static_cast<int>(i), cv::Scalar(255), cv::FILLED);
  }
  cv::erode(overlay, overlay, join);
  // Thin lines (edges of the scene that happened to stay still, a still border stretch) are
  // not overlays: text and parts are blocks once closed.
  cv::morphologyEx(overlay, overlay, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  cv::Mat labels;
  out.regions = cv::connectedComponents(overlay, labels) - 1;
  if (options_.dilate_px > 0) {
    const cv::Mat kernel = cv::getStructuringElement(
        cv::MORPH_ELLIPSE, {2 * options_.dilate_px + 1, 2 * options_.dilate_px + 1});
    cv::dilate(overlay, overlay, kernel);
  }
  out.masked_fraction = cv::countNonZero(overlay) / pixels;
  cv::bitwise_not(overlay, out.mask);
  mean_.convertTo(out.mean, CV_8U);
  return out;
}

OverlayDetection detectInVideos(const std::vector<fs::path>& videos,
                                const OverlayOptions& options) {
  options.check();
  std::vector<int> counts;
  long total = 0;
  for (const fs::path& video : videos) {
    int count = keyframes::expectedFrameCount(video);
    if (count <= 0) {  // unknown: count by decoding
      cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
      if (!capture.isOpened()) throw std::runtime_error(video.string() + ": cannot open the video");
      count = 0;
      while (capture.grab()) ++count;
    }
    counts.push_back(count);
    total += count;
  }
  if (total <= 0) throw std::runtime_error("overlay: the videos hold no frame");
  OverlayDetector detector(options);
  const int samples = static_cast<int>(std::min<long>(options.samples, total));
  long first = 0;  // global index of the current video's frame 0
  int next = 0;    // next sample
  for (size_t v = 0; v < videos.size(); ++v) {
    cv::VideoCapture capture(videos[v].string(), cv::CAP_FFMPEG);
    if (!capture.isOpened()) {
      throw std::runtime_error(videos[v].string() + ": cannot open the video");
    }
    int read = 0, wanted = 0;
    for (; next < samples; ++next) {
      const long global = static_cast<long>((next + 0.5) * total / samples);
      if (global >= first + counts[v]) break;
      ++wanted;
      cv::Mat frame;
      capture.set(cv::CAP_PROP_POS_FRAMES, static_cast<double>(global - first));
      if (!capture.read(frame) || frame.empty()) continue;  // a count past the real end
      try {
        detector.add(frame);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(videos[v].string() + ": " + e.what());
      }
      ++read;
    }
    if (wanted > 0 && read == 0) {
      throw std::runtime_error(videos[v].string() + ": no frame could be decoded");
    }
    first += counts[v];
  }
  return detector.detect();
}

}  // namespace auv::recon::overlay
