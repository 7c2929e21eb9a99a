#include "auv/recon/keyframes/selector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::keyframes {

namespace {
double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<long>(mid), values.end());
  return values[mid];
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f", value);
  return text;
}
}  // namespace

std::string triggerName(Trigger trigger) {
  switch (trigger) {
    case Trigger::START:
      return "start";
    case Trigger::MOTION:
      return "motion";
    case Trigger::TRACKING_LOST:
      return "tracking_lost";
  }
  return "?";
}

void KeyframeOptions::check() const {
  AUV_RECON_CHECK_OPTION(analysis_width == 0 || analysis_width >= 64, analysis_width,
                         "must be 0 (full resolution) or >= 64 px");
  AUV_RECON_CHECK_OPTION(min_motion > 0 && min_motion <= 1, min_motion,
                         "must be in (0, 1] (fraction of the image width)");
  AUV_RECON_CHECK_OPTION(min_tracked_fraction >= 0 && min_tracked_fraction < 1,
                         min_tracked_fraction, "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(max_features >= 10, max_features, "must be >= 10");
  AUV_RECON_CHECK_OPTION(feature_quality > 0 && feature_quality < 1, feature_quality,
                         "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(feature_min_distance >= 0 && feature_min_distance < 0.5,
                         feature_min_distance, "must be in [0, 0.5) (fraction of the width)");
  AUV_RECON_CHECK_OPTION(lk_window >= 5 && lk_window <= 101 && lk_window % 2 == 1, lk_window,
                         "must be odd, in [5, 101] px");
  AUV_RECON_CHECK_OPTION(lk_levels >= 0 && lk_levels <= 8, lk_levels, "must be in [0, 8]");
  AUV_RECON_CHECK_OPTION(max_fb_error >= 0 && std::isfinite(max_fb_error), max_fb_error,
                         "must be >= 0 px (0 = no forward-backward check)");
  AUV_RECON_CHECK_OPTION(candidate_frames >= 1, candidate_frames, "must be >= 1");
  AUV_RECON_CHECK_OPTION(max_candidate_frames >= candidate_frames, max_candidate_frames,
                         "must be >= candidate_frames");
  AUV_RECON_CHECK_OPTION(min_brightness >= 0 && min_brightness < 255, min_brightness,
                         "must be in [0, 255) (mean grey level)");
  AUV_RECON_CHECK_OPTION(min_sharpness >= 0 && std::isfinite(min_sharpness), min_sharpness,
                         "must be >= 0");
  AUV_RECON_CHECK_OPTION(min_relative_sharpness >= 0 && min_relative_sharpness <= 1,
                         min_relative_sharpness, "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(sharpness_history >= 1, sharpness_history, "must be >= 1");
  AUV_RECON_CHECK_OPTION(min_features >= 1 && min_features <= max_features, min_features,
                         "must be in [1, max_features]");
}

KeyframeSelector::KeyframeSelector(const KeyframeOptions& options) : options_(options) {
  options_.check();
}

double KeyframeSelector::sharpness(const cv::Mat& gray) {
  cv::Mat laplacian;
  cv::Laplacian(gray, laplacian, CV_16S, 1);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  return deviation[0] * deviation[0];
}

cv::Mat KeyframeSelector::analysisImage(const cv::Mat& image) const {
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  if (scale_ == 1.0) return gray.clone();
  cv::Mat small;
  cv::resize(gray, small, cv::Size(), scale_, scale_, cv::INTER_AREA);
  return small;
}

void KeyframeSelector::track(const cv::Mat& small) {
  if (points_.empty() || prev_.empty()) return;
  const cv::Size window(options_.lk_window, options_.lk_window);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.03);
  std::vector<cv::Point2f> next, back;
  std::vector<uchar> status, back_status;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(prev_, small, points_, next, status, error, window, options_.lk_levels,
                           criteria);
  if (options_.max_fb_error > 0) {
    // Forward-backward check (Kalal et al. 2010): a point tracked back must land where it
    // started, else LK converged on something else (a new scene, an occlusion).
    back = points_;
    cv::calcOpticalFlowPyrLK(small, prev_, next, back, back_status, error, window,
                             options_.lk_levels, criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
  }
  size_t kept = 0;
  for (size_t i = 0; i < next.size(); ++i) {
    const cv::Point2f& p = next[i];
    if (!status[i] || p.x < 0 || p.y < 0 || p.x > small.cols - 1 || p.y > small.rows - 1) continue;
    if (options_.max_fb_error > 0 &&
        (!back_status[i] || cv::norm(back[i] - points_[i]) > options_.max_fb_error)) {
      continue;
    }
    points_[kept] = p;
    reference_[kept] = reference_[i];
    ++kept;
  }
  points_.resize(kept);
  reference_.resize(kept);
}

double KeyframeSelector::motionPx() const {
  if (points_.empty()) return 0;
  std::vector<double> moved(points_.size());
  for (size_t i = 0; i < points_.size(); ++i) moved[i] = cv::norm(points_[i] - reference_[i]);
  return median(std::move(moved)) / scale_;
}

std::optional<Keyframe> KeyframeSelector::addFrame(int frame, const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U) {
    throw std::invalid_argument("KeyframeSelector: frame " + std::to_string(frame) +
                                " is empty or not 8-bit");
  }
  if (full_width_ == 0) {
    full_width_ = image.cols;
    scale_ = options_.analysis_width > 0 && image.cols > options_.analysis_width
                 ? static_cast<double>(options_.analysis_width) / image.cols
                 : 1.0;
    if (!mask_.empty()) {
      if (mask_.size() != image.size() || mask_.type() != CV_8UC1) {
        throw std::invalid_argument(
            "KeyframeSelector: the mask is not 8-bit grey of the frames' "
            "size");
      }
      cv::resize(mask_, small_mask_, cv::Size(), scale_, scale_, cv::INTER_NEAREST);
    }
  } else if (image.cols != full_width_) {
    throw std::invalid_argument("KeyframeSelector: frame " + std::to_string(frame) + " is " +
                                std::to_string(image.cols) + " px wide, the first was " +
                                std::to_string(full_width_));
  }
  ++counts_.frames;
  cv::Mat small = analysisImage(image);
  const double frame_sharpness = sharpness(small);
  if (!has_reference_) {
    prev_ = small;
  } else if (frame_sharpness < options_.min_relative_sharpness * reference_sharpness_ &&
             skipped_ < options_.max_candidate_frames) {
    // A blurred frame (motion blur, a jolt): features tracked into it are lost or misplaced,
    // which would look like a new scene. Track over it, from the last sharp frame.
    ++skipped_;
    ++counts_.frames_not_tracked;
  } else {
    track(small);
    prev_ = small;
    skipped_ = 0;
  }
  const double motion = motionPx();
  const int tracked = static_cast<int>(points_.size());

  if (!window_open_) {
    if (!has_reference_) {
      window_trigger_ = Trigger::START;
    } else if (motion >= options_.min_motion * full_width_) {
      window_trigger_ = Trigger::MOTION;
      ++counts_.triggers_motion;
    } else if (tracked < options_.min_tracked_fraction * reference_features_) {
      window_trigger_ = Trigger::TRACKING_LOST;
      ++counts_.triggers_tracking;
    } else {
      return std::nullopt;
    }
    window_open_ = true;
  }

  cv::Scalar mean = cv::mean(small);
  window_.push_back({frame, small, frame_sharpness, mean[0], motion, tracked});
  ++counts_.candidates;
  const Candidate& c = window_.back();
  if (c.brightness >= options_.min_brightness &&
      (best_ < 0 || c.sharpness > window_[static_cast<size_t>(best_)].sharpness)) {
    best_ = static_cast<int>(window_.size()) - 1;
    image.copyTo(best_image_);
  }
  return evaluateWindow(false);
}

std::optional<Keyframe> KeyframeSelector::finish() {
  if (!window_open_) return std::nullopt;
  return evaluateWindow(true);
}

std::optional<Keyframe> KeyframeSelector::evaluateWindow(bool end_of_video) {
  double threshold = options_.min_sharpness;
  if (!history_.empty()) {
    threshold = std::max(threshold, options_.min_relative_sharpness * median(history_));
  }
  const bool best_usable = best_ >= 0 && window_[static_cast<size_t>(best_)].sharpness >= threshold;
  const int size = static_cast<int>(window_.size());
  if (best_usable && (size >= options_.candidate_frames || end_of_video)) {
    return select(static_cast<size_t>(best_), window_trigger_, threshold);
  }
  if (!end_of_video && size < options_.max_candidate_frames) return std::nullopt;
  if (!end_of_video && best_ >= 0 &&
      window_[static_cast<size_t>(best_)].sharpness >= options_.min_sharpness) {
    // Refused only relative to earlier keyframes for a whole long window: the scene's texture
    // changed (e.g. rock to sand), the old sharpness is no reference any more.
    history_.clear();
    ++counts_.reference_resets;
    const double reset_threshold =
        std::max(options_.min_sharpness,
                 options_.min_relative_sharpness * window_[static_cast<size_t>(best_)].sharpness);
    return select(static_cast<size_t>(best_), window_trigger_, reset_threshold);
  }
  // Nothing usable: every candidate is reported, the window dropped (tracking goes on against
  // the old keyframe, so the next frame opens a new window).
  for (const Candidate& c : window_) {
    if (c.brightness < options_.min_brightness) {
      rejected_.push_back({c.frame, "dark",
                           "mean grey " + number(c.brightness) + " < " +
                               number(options_.min_brightness) + " (min_brightness)",
                           c.sharpness, c.brightness});
      ++counts_.rejected_dark;
    } else {
      rejected_.push_back({c.frame, "blurry",
                           "sharpness " + number(c.sharpness) + " < " + number(threshold),
                           c.sharpness, c.brightness});
      ++counts_.rejected_blurry;
    }
  }
  ++counts_.windows_dropped;
  closeWindow();
  return std::nullopt;
}

std::optional<Keyframe> KeyframeSelector::select(size_t best, Trigger trigger, double threshold) {
  for (size_t i = 0; i < window_.size(); ++i) {
    const Candidate& c = window_[i];
    if (i == best) continue;
    if (c.brightness < options_.min_brightness) {
      rejected_.push_back({c.frame, "dark",
                           "mean grey " + number(c.brightness) + " < " +
                               number(options_.min_brightness) + " (min_brightness)",
                           c.sharpness, c.brightness});
      ++counts_.rejected_dark;
    } else if (c.sharpness < threshold) {
      rejected_.push_back({c.frame, "blurry",
                           "sharpness " + number(c.sharpness) + " < " + number(threshold) +
                               (history_.empty() ? std::string(" (min_sharpness)")
                                                 : " (min_relative_sharpness x median of the "
                                                   "last keyframes; min_sharpness)"),
                           c.sharpness, c.brightness});
      ++counts_.rejected_blurry;
    }
  }
  const Candidate& chosen = window_[best];
  std::vector<cv::Point2f> corners;
  const double min_distance = std::max(1.0, options_.feature_min_distance * chosen.small.cols);
  cv::goodFeaturesToTrack(chosen.small, corners, options_.max_features, options_.feature_quality,
                          min_distance, small_mask_.empty() ? cv::noArray() : small_mask_);
  if (static_cast<int>(corners.size()) < options_.min_features) {
    // Tracking goes on against the previous keyframe (if any): the next frame opens a new
    // window.
    rejected_.push_back({chosen.frame, "featureless",
                         std::to_string(corners.size()) + " corners < " +
                             std::to_string(options_.min_features) + " (min_features)",
                         chosen.sharpness, chosen.brightness});
    ++counts_.rejected_featureless;
    closeWindow();
    return std::nullopt;
  }
  Keyframe keyframe;
  keyframe.frame = chosen.frame;
  keyframe.image = std::move(best_image_);
  best_image_ = cv::Mat();
  keyframe.trigger = trigger;
  keyframe.sharpness = chosen.sharpness;
  keyframe.brightness = chosen.brightness;
  keyframe.motion_px = chosen.motion_px;
  keyframe.tracked = chosen.tracked;
  keyframe.features = static_cast<int>(corners.size());
  history_.push_back(chosen.sharpness);
  if (static_cast<int>(history_.size()) > options_.sharpness_history) {
    history_.erase(history_.begin());
  }
  startReference(std::move(corners), best);
  reference_sharpness_ = chosen.sharpness;
  closeWindow();
  return keyframe;
}

void KeyframeSelector::closeWindow() {
  window_.clear();
  window_open_ = false;
  best_ = -1;
}

void KeyframeSelector::startReference(std::vector<cv::Point2f> corners, size_t window_position) {
  reference_ = corners;
  points_ = std::move(corners);
  reference_features_ = static_cast<int>(points_.size());
  has_reference_ = true;
  // Bring the new features up to the newest frame through the rest of the window (over the
  // blurred frames, as in addFrame).
  const Candidate& keyframe = window_[window_position];
  prev_ = keyframe.small;
  skipped_ = 0;
  for (size_t j = window_position + 1; j < window_.size(); ++j) {
    if (window_[j].sharpness < options_.min_relative_sharpness * keyframe.sharpness) {
      ++skipped_;
      continue;
    }
    track(window_[j].small);
    prev_ = window_[j].small;
    skipped_ = 0;
  }
}

}  // namespace auv::recon::keyframes
