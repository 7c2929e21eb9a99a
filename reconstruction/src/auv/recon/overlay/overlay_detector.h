#pragma once
// Static-overlay detection (issue 20 part 3): burned-in timestamps and depth read-outs, the
// housing's edge or the vehicle's own parts stay put on the image while the scene moves under
// them. Over frames sampled across a camera's videos, a pixel whose grey level keeps still
// (temporal standard deviation below `max_std`) and that lies on an edge of the temporal mean
// image (the moving scene blurs out of the mean, a fixed overlay stays sharp) seeds the mask,
// and so does a pixel that barely varies at all (`max_std_flat`: the flat inside of a dark box
// on dark footage, whose edges are too faint);
// the seeds are closed into blocks (text strokes join), holes are filled (the inside of a
// read-out box), small blobs dropped and the rest dilated by a margin (SIFT descriptors reach
// beyond their keypoint). The result is a mask in COLMAP's convention (masks/mask.h): 0 on the
// overlay, 255 elsewhere.

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::overlay {

struct OverlayOptions {
  /// Frames sampled evenly over the camera's videos.
  int samples = 60;
  /// Grey levels (0-255): a pixel whose temporal standard deviation is below this is static.
  double max_std = 6.0;
  /// Grey levels per px: the temporal mean image's gradient (Sobel / 4) above which a static
  /// pixel is an overlay edge.
  double min_gradient = 12.0;
  /// Grey levels: a pixel whose temporal standard deviation is below this is an overlay pixel
  /// whatever its contrast (a dark read-out box or housing on dark footage has no edge above
  /// min_gradient; the moving scene's pixels, even its dark ones, vary more). 0 = edges only.
  double max_std_flat = 1.0;
  /// px: closing that joins the strokes of text into one block.
  int close_px = 15;
  /// px: static blobs smaller than this (after closing) are dropped as chance.
  int min_area_px = 100;
  /// px: margin added around the overlay.
  int dilate_px = 6;
  /// The scene must move: at least this fraction of the pixels must vary by more than
  /// 2 x max_std, else a static overlay cannot be told from a static scene.
  double min_moving_fraction = 0.3;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

struct OverlayDetection {
  cv::Mat mask;                ///< CV_8U, 0 on the overlay, 255 elsewhere
  cv::Mat mean;                ///< CV_8U temporal mean of the grey frames (for inspection)
  int frames = 0;              ///< frames the statistics are over
  double moving_fraction = 0;  ///< pixels varying by more than 2 x max_std
  double masked_fraction = 0;  ///< of the image
  int regions = 0;             ///< connected overlay regions kept
};

/// Per-pixel temporal statistics of frames of one camera (all of one size), then the mask.
class OverlayDetector {
 public:
  explicit OverlayDetector(const OverlayOptions& options);
  /// Adds a frame (8-bit grey or BGR). Throws std::invalid_argument when its size differs
  /// from the first frame's.
  void add(const cv::Mat& frame);
  int frames() const { return frames_; }
  /// The mask of the frames added (at least 2). Throws std::runtime_error when the scene does
  /// not move enough (moving_fraction < min_moving_fraction), saying how much it moved.
  OverlayDetection detect() const;

 private:
  OverlayOptions options_;
  int frames_ = 0;
  cv::Mat mean_, m2_;  ///< CV_64F, Welford's running mean and sum of squared deviations
};

/// The frames of a list of videos (one camera, in order), `options.samples` of them evenly
/// spaced over their total length, through an OverlayDetector. Throws std::runtime_error naming a
/// video that cannot be opened or read.
OverlayDetection detectInVideos(const std::vector<std::filesystem::path>& videos,
                                const OverlayOptions& options);

}  // namespace auv::recon::overlay
