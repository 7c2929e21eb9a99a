#pragma once
// Keyframe selection of one video (paper section 3.1, after Cavan [43]): Shi-Tomasi minimum-
// eigenvalue corners [45] of the last keyframe are tracked frame to frame with pyramidal
// Lucas-Kanade [44]; when their median displacement since the keyframe exceeds a threshold, or
// too few of them survive, a new keyframe is due, and it is chosen among a few consecutive
// candidate frames as the one with the highest variance of the Laplacian (the sharpest [35]).
// Candidates too dark or too blurry are refused and reported, never used.
//
// The selector is fed one frame at a time (the caller streams the video) and keeps only small
// grey copies of the current candidate window and one full-resolution frame (the best
// candidate so far).

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::keyframes {

struct KeyframeOptions {
  /// px: frames wider than this are reduced (area averaging) for tracking and the sharpness
  /// score; 0 = full resolution. Thresholds below are in full-resolution px or fractions.
  int analysis_width = 960;
  /// New keyframe when the median displacement of the tracked features since the last
  /// keyframe reaches this fraction of the image width (the paper's per-video threshold).
  double min_motion = 0.15;
  /// New keyframe when fewer than this fraction of the keyframe's features are still tracked.
  double min_tracked_fraction = 0.4;
  /// Shi-Tomasi corners detected in each keyframe (cv::goodFeaturesToTrack).
  int max_features = 400;
  /// Corner quality: fraction of the strongest corner's minimum eigenvalue.
  double feature_quality = 0.01;
  /// Minimum distance between corners, fraction of the analysis width.
  double feature_min_distance = 0.012;
  int lk_window = 21;  ///< px at the analysis resolution, Lucas-Kanade window side
  int lk_levels = 3;   ///< pyramid levels above the analysis image
  /// px at the analysis resolution: a feature tracked back to the previous frame must land
  /// this close to where it was (forward-backward check), else it is lost. 0 = no check.
  double max_fb_error = 1.0;
  /// Consecutive frames, from the one that triggers, compared by sharpness.
  int candidate_frames = 5;
  /// While every candidate is refused the window grows, up to this many frames; then the
  /// blur reference is reset (the scene's texture changed) and the sharpest frame above
  /// `min_sharpness` is taken, or, if none, the window is dropped and a new one opened.
  int max_candidate_frames = 30;
  /// Mean grey level (0-255) below which a frame is refused as too dark.
  double min_brightness = 15;
  /// Variance of the Laplacian (of the 8-bit grey analysis image) below which a frame is
  /// refused as too blurry, whatever the scene.
  double min_sharpness = 3;
  /// A frame is refused as too blurry when its sharpness is below this fraction of the median
  /// sharpness of the last `sharpness_history` keyframes (motion blur, focus hunting).
  double min_relative_sharpness = 0.4;
  int sharpness_history = 5;
  /// A chosen frame with fewer Shi-Tomasi corners than this is refused as featureless (open
  /// water, a lens against a wall): nothing to track from it or to match in SfM.
  int min_features = 20;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// Why a keyframe was taken.
enum class Trigger { START, MOTION, TRACKING_LOST };
std::string triggerName(Trigger trigger);

struct Keyframe {
  int frame = 0;  ///< index in the video
  cv::Mat image;  ///< the frame as decoded (full resolution)
  Trigger trigger = Trigger::START;
  double sharpness = 0;   ///< variance of the Laplacian (analysis resolution)
  double brightness = 0;  ///< mean grey level 0-255
  double motion_px = 0;   ///< median feature displacement since the previous keyframe, px
  int tracked = 0;        ///< previous keyframe's features still tracked at this frame
  int features = 0;       ///< corners detected in this keyframe
};

struct RejectedFrame {
  int frame = 0;
  std::string reason;  ///< "dark", "blurry" or "featureless"
  std::string detail;  ///< the numbers: "sharpness 12.1 < 30.4 (0.4 x median of keyframes)"
  double sharpness = 0, brightness = 0;
};

struct SelectorCounts {
  int frames = 0;      ///< frames fed
  int candidates = 0;  ///< frames evaluated as candidates
  int rejected_dark = 0, rejected_blurry = 0, rejected_featureless = 0;
  int triggers_motion = 0, triggers_tracking = 0;
  int reference_resets = 0;    ///< windows that outgrew max_candidate_frames
  int windows_dropped = 0;     ///< windows without any usable frame
  int frames_not_tracked = 0;  ///< blurred frames the tracking jumped over
};

class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeOptions& options);

  /// Feeds the next frame (8-bit BGR or grey, every frame of the video, in order; `frame` its
  /// index). Returns the keyframe this frame completes, if any (it is an earlier or this frame).
  std::optional<Keyframe> addFrame(int frame, const cv::Mat& image);
  /// End of the video: an open candidate window yields its keyframe if one is usable.
  std::optional<Keyframe> finish();

  /// Frames refused so far (appended as windows close).
  const std::vector<RejectedFrame>& rejected() const { return rejected_; }
  const SelectorCounts& counts() const { return counts_; }

  /// A mask of the frames (CV_8U of their full size, 0: ignore; masks/mask.h): no corner is
  /// tracked there, so a burned-in overlay, which never moves, neither holds the median motion
  /// at zero nor keeps features "tracked" through a new scene. Set before the first frame.
  void setMask(const cv::Mat& mask) { mask_ = mask; }

  /// Variance of the Laplacian of an 8-bit grey image (the paper's blur score).
  static double sharpness(const cv::Mat& gray);

 private:
  struct Candidate {
    int frame;
    cv::Mat small;  ///< grey, analysis resolution
    double sharpness, brightness, motion_px;
    int tracked;
  };
  cv::Mat analysisImage(const cv::Mat& image) const;
  void track(const cv::Mat& small);  ///< prev_ -> small, updates points_ and the motion
  double motionPx() const;
  std::optional<Keyframe> evaluateWindow(bool end_of_video);
  std::optional<Keyframe> select(size_t best, Trigger trigger, double threshold);
  void closeWindow();
  void startReference(std::vector<cv::Point2f> corners, size_t window_position);

  KeyframeOptions options_;
  double scale_ = 1;    ///< analysis px per full-resolution px
  int full_width_ = 0;  ///< px of the first frame
  cv::Mat mask_;        ///< full resolution, empty: none
  cv::Mat small_mask_;  ///< at the analysis resolution
  // Tracking state: features of the last keyframe (reference_) and where they are now.
  bool has_reference_ = false;
  std::vector<cv::Point2f> reference_, points_;
  int reference_features_ = 0;
  double reference_sharpness_ = 0;  ///< of the last keyframe
  int skipped_ = 0;                 ///< blurred frames tracked over since prev_
  cv::Mat prev_;                    ///< last frame tracked into
  // The open candidate window.
  bool window_open_ = false;
  Trigger window_trigger_ = Trigger::START;
  std::vector<Candidate> window_;
  int best_ = -1;                ///< sharpest non-dark candidate of the window
  cv::Mat best_image_;           ///< its full-resolution frame
  std::vector<double> history_;  ///< sharpness of the last keyframes
  std::vector<RejectedFrame> rejected_;
  SelectorCounts counts_;
};

}  // namespace auv::recon::keyframes
