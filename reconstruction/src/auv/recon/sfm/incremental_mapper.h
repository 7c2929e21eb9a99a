#pragma once
// Incremental structure from motion (paper section 3.4.2; the scheme of Schoenberger & Frahm,
// "Structure-from-Motion Revisited", CVPR 2016, that COLMAP implements, and of Moulon et al.'s
// openMVG): an initial pair with a wide baseline that is not planar, then one view at a time
// resected from the points it sees (P3P in a robust loop + non-linear refinement), new points
// triangulated with angle and reprojection checks, bundle adjustment with Ceres locally after
// each view and globally as the model grows, re-triangulation and outlier filtering after it.
// Loop closures need nothing special: the tracks join every verified pair, sequential or not.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "auv/recon/scene/reconstruction.h"
#include "auv/recon/sfm/bundle_adjustment.h"
#include "auv/recon/sfm/correspondences.h"
#include "auv/recon/sfm/robust_geometry.h"

namespace auv::recon {
class Progress;
}

namespace auv::recon::sfm {

struct MapperOptions {
  // Initial pair.
  size_t init_min_inliers = 100;           ///< essential-matrix inliers the initial pair needs
  double init_min_tri_angle_deg = 16;      ///< deg: median triangulation angle of its points
  double init_max_homography_ratio = 0.8;  ///< homography / essential inliers above: planar
  size_t init_max_pairs = 40;              ///< candidate pairs tried (most matches first)
  int init_relaxations = 2;  ///< times the angle is halved when no pair passes; a last round
                             ///< then also accepts planar pairs (flat sea floor)

  // Registration of a new view.
  size_t abs_pose_min_inliers = 20;        ///< 2D-3D inliers a resected view needs
  double abs_pose_min_inlier_ratio = 0.2;  ///< inliers / correspondences it needs
  int max_registration_trials = 2;         ///< failed resections before a view is left out

  // Triangulation and filtering.
  double min_tri_angle_deg = 1.5;          ///< deg: largest angle in a point's track
  double max_reprojection_error_px = 4.0;  ///< px: observations beyond are outliers
  /// Leave tracks seen by only two images of the whole survey untriangulated, except in the
  /// initial pair (COLMAP's ignore_two_view_tracks): such a point can never help register a
  /// third view, constrains bundle adjustment least, and is the likeliest to be a wrong match.
  /// On Sceaux they were 11 194 of 18 813 points (mean track length 2.9 against COLMAP's 4.8).
  bool ignore_two_view_tracks = true;

  // Bundle adjustment.
  size_t local_ba_images = 6;         ///< the new view and its best-connected neighbours
  double global_ba_growth = 0.1;      ///< global BA when registered views grew by this fraction
  int local_ba_max_iterations = 25;   ///< Levenberg-Marquardt iterations of a local BA
  int global_ba_max_iterations = 50;  ///< and of a global one
  BundleAdjustmentOptions ba;         ///< loss, scale, tolerance, threads

  // Self-calibration of the input's uncalibrated cameras (global BA only, as COLMAP).
  bool refine_focal_length = true;      ///< refine their focal length (shared per camera)
  bool refine_principal_point = false;  ///< and their principal point (weakly observed)
  /// and their radial distortion k1, k2 (OpenCV model): a phone or action camera's lens is
  /// rarely free of it, and a focal refined without it absorbs it (Sceaux: +7.3 % without).
  bool refine_radial_distortion = true;
  bool refine_tangential_distortion = false;  ///< and p1, p2 (weakly observed)
  /// A refined focal beyond this factor of the prior (either way), a radial distortion that
  /// folds the image or scales its corners beyond 50 %, or a principal point outside the
  /// middle half of the image, has run away: it is reset to the prior, flagged, and the
  /// camera keeps the prior for the rest of the run.
  double max_focal_ratio = 2.0;

  RobustOptions robust;  ///< P3P / essential / homography fits

  /// Throws OptionError naming the field and value.
  void check() const;
};

enum class MapperStatus { SUCCESS, NO_INITIAL_PAIR, NO_INPUT };
std::string mapperStatusName(MapperStatus status);

/// Seconds per sub-stage.
struct MapperTimings {
  double tracks = 0, initial_pair = 0, registration = 0, triangulation = 0, local_ba = 0,
         global_ba = 0, filtering = 0, total = 0;
};

struct MapperResult {
  MapperStatus status = MapperStatus::NO_INPUT;
  std::string message;  ///< why, with the numbers, when not SUCCESS
  scene::Reconstruction reconstruction;
  size_t images_total = 0;
  std::vector<uint32_t> unregistered;  ///< image ids left out
  /// Why each one was left out ("no verified pair", "12 inliers of 51 2D-3D correspondences
  /// (needs >= 20 and >= 20 %)", ...): what a user changes next.
  std::map<uint32_t, std::string> unregistered_reasons;
  std::pair<uint32_t, uint32_t> initial_pair{0, 0};
  TrackStats tracks;
  size_t local_bas = 0, global_bas = 0;
  MapperTimings timings;
  /// Uncalibrated cameras whose refinement ran away and were reset to the prior, and why.
  std::map<uint32_t, std::string> intrinsics_reset;
};

class IncrementalMapper {
 public:
  /// Checks `input` (std::invalid_argument) and `options` (OptionError).
  IncrementalMapper(SfmInput input, MapperOptions options);

  /// Reconstructs one model from the initial pair outwards. `progress` (may be null) counts
  /// registered images; `log` (may be null) receives one line per notable event.
  MapperResult run(Progress* progress = nullptr,
                   const std::function<void(const std::string&)>& log = nullptr);

 private:
  /// A candidate initial pair and, once evaluated, its two-view geometry.
  struct PairCandidate {
    uint32_t a = 0, b = 0;
    size_t matches = 0;
    int64_t homography_inliers = -1;           ///< from the verification, -1: unknown
    std::optional<Eigen::Matrix3d> essential;  ///< from the verification
    bool evaluated = false;
    RelativePose pose;
    size_t correspondences = 0;
    double homography_ratio = 1;  ///< homography inliers / essential inliers
    double median_angle = 0;      ///< rad, of the inliers triangulated in front of both
  };

  /// Tries the candidates, most matches first, against the thresholds, relaxed in rounds.
  bool findInitialPair(MapperResult& result);
  void evaluatePair(PairCandidate& pair);
  void buildInitialPair(const PairCandidate& pair);
  void addImage(uint32_t id, const Eigen::Quaterniond& q_cw, const Eigen::Vector3d& t_cw);
  bool registerImage(uint32_t id);
  /// Triangulates the new tracks of an image and completes existing points it sees.
  size_t triangulateImage(uint32_t id);
  /// `initial`: the initial pair's, which triangulates its two-view tracks too.
  bool triangulateTrack(uint64_t track, bool initial = false);
  size_t completePoint(uint64_t track);
  void addObservation(uint64_t point, const scene::TrackElement& element);
  void deletePoint(uint64_t point);
  /// Removes observations beyond the error threshold / behind cameras and points whose track
  /// got too short or too narrow. Returns the observations removed.
  size_t filterPoints(const std::set<uint64_t>& points);
  void localBundleAdjustment(uint32_t id, MapperResult& result);
  /// `timed`: counted as global BA time (the initial pair's two-view BA counts as initial pair).
  /// Resets camera `id` to its prior when its refinement ran away (MapperOptions).
  void resetRunawayIntrinsics(uint32_t id, MapperResult& result);
  /// The images in groups that verified pairs join to each other but not to the model, with
  /// their group's size (computed once, after mapping).
  std::map<uint32_t, size_t> separateGroups() const;
  /// Why view `id` is not registered, for MapperResult::unregistered_reasons.
  std::string whyUnregistered(uint32_t id, const std::map<uint32_t, size_t>& separate) const;
  void globalBundleAdjustment(MapperResult& result, int max_iterations, bool timed = true);
  /// Triangulates every track not yet in the model and completes every point.
  size_t retriangulate();
  std::vector<uint32_t> nextCandidates() const;
  double reprojectionError(const scene::Image& image, uint32_t keypoint,
                           const Eigen::Vector3d& xyz) const;
  double maxTriangulationAngle(const scene::Point3D& point) const;
  void logLine(const std::string& line) const;

  SfmInput input_;
  MapperOptions options_;
  Tracks tracks_;
  std::map<uint32_t, const View*> views_;
  scene::Reconstruction rec_;
  std::map<uint32_t, int> failed_trials_;
  std::map<uint32_t, std::string> last_failure_;  ///< of registerImage, per view
  std::vector<PairCandidate> pair_candidates_;
  std::pair<uint32_t, uint32_t> initial_pair_{0, 0};
  MapperTimings* timings_ = nullptr;
  std::function<void(const std::string&)> log_;
};

}  // namespace auv::recon::sfm
