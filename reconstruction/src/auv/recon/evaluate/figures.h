#pragma once
// `auv recon figures <survey>`: the paper's Figures 19 and 20 for a survey.
//   (a) per-camera contribution (Figure 19a): the cloud coloured by the combination of cameras
//       whose images produced each point, top-down (figures/cameras.png) and as a coloured
//       cloud (figures/cameras.ply). Dense cloud when dense/fused_views.bin gives each fused
//       point's images, else the sparse cloud from its tracks.
//   (b) trajectory comparison (Figure 20): the vehicle's navigation estimate against the SfM
//       camera trajectory, over the true trajectory and a top-down relief of the true world
//       (figures/trajectory.png and .svg). Needs the ground-truth run (navigation.tum and the
//       alignment; the paper had to guess the scale by hand, section 4.3). Framed with at least
//       4 m of relief around the paths and width:height within 1:2 and 2:1, so a long straight
//       traverse still shows what lies beside it (the walls of a canyon).
// Both images are made large enough for their legend (text measured, never cut).
// Top-down = looking down the world's z axis (NED, north up) once aligned to the truth;
// without ground truth, down the cloud's axis of least spread.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/common/survey.h"

namespace auv::recon::evaluate {

struct FiguresOptions {
  int image_size_px = 1600;    ///< px, the longer side of the top-down images
  int point_size_px = 2;       ///< px, side of a drawn point
  std::string cloud = "auto";  ///< auto (dense when it has views, else sparse), dense or sparse

  /// Throws OptionError naming the field.
  void check() const;
};

/// Colour (BGR) of a camera combination: bit i = the i-th camera of `cameras` (sorted names).
/// One camera: red, green, blue; two: their mixtures (yellow, magenta, cyan); three: white;
/// more cameras: distinct hues.
cv::Vec3b combinationColor(uint32_t mask, size_t camera_count);
/// "left + forward" for a mask over `cameras`.
std::string combinationName(uint32_t mask, const std::vector<std::string>& cameras);

/// How a TopDownView frames its points beyond their bounds.
struct TopDownFraming {
  double margin = 0.05;       ///< fraction of the points' extent added on each side
  double min_margin_m = 0.0;  ///< m, at least this much added on each side
  double min_aspect = 0.0;    ///< in [0, 1]: the shorter side at least this fraction of the
                              ///< longer one (widened about the centre)
  cv::Size min_size_px;       ///< px, the image at least this large (room for the legend): more
                              ///< of the world about the centre, same scale
};

/// Maps world points to the pixels of a top-down image: north (x) up, east (y) right, the
/// framed bounds of `points` filling `size_px` on the longer side (more only when
/// `framing.min_size_px` asks for it).
class TopDownView {
 public:
  /// Throws std::invalid_argument on a negative margin or a min_aspect outside [0, 1].
  TopDownView(const std::vector<Eigen::Vector2d>& points, int size_px,
              const TopDownFraming& framing = {});
  cv::Point2f pixel(const Eigen::Vector2d& xy) const;  ///< xy = (north, east)
  cv::Size size() const { return size_; }
  double pixelsPerMetre() const { return scale_; }

 private:
  Eigen::Vector2d min_, max_;
  double scale_ = 1;
  cv::Size size_;
};

/// Draws `points` (x, y, depth z) top-down into a new image: deepest first, so what is seen from
/// above covers what lies below. Background dark grey; a legend of the colours used.
cv::Mat drawTopDownCloud(const std::vector<Eigen::Vector3d>& points,
                         const std::vector<cv::Vec3b>& colors, const TopDownView& view,
                         int point_size_px);

using LegendEntry = std::pair<cv::Vec3b, std::string>;  ///< colour (BGR), label

/// Font scale (cv::FONT_HERSHEY_SIMPLEX) of legends on an image whose longer side is `size_px`.
double legendFontScale(int size_px);
/// The smallest image (px) that holds drawLegend's box and scale bar, text measured with
/// cv::getTextSize: give it to TopDownFraming::min_size_px so no label is ever cut.
cv::Size legendImageSize(const std::vector<LegendEntry>& entries, double font_scale);
/// A legend box (colour, label) in the top-left corner and a scale bar (m) bottom-left; returns
/// the box. Throws std::invalid_argument when `image` is smaller than legendImageSize().
cv::Rect drawLegend(cv::Mat& image, const std::vector<LegendEntry>& entries,
                    double pixels_per_metre, double font_scale);

struct FiguresStageResult {
  std::vector<std::filesystem::path> files;
  std::string cloud;  ///< "dense" or "sparse"
  std::map<std::string, size_t> points_per_combination;
  size_t points = 0;
  bool trajectory = false;  ///< (b) drawn (needs the ground truth)
};

/// Writes the figures into <survey>/figures/ (replaced as a whole: StagedOutput). With an empty
/// `ground_truth_run`, only (a) in the reconstruction's own frame. Throws StageError
/// ("figures", ...) when the survey has no sparse model or no point with a camera.
FiguresStageResult writeFigures(const Survey& survey, const std::filesystem::path& ground_truth_run,
                                const FiguresOptions& options);

}  // namespace auv::recon::evaluate
