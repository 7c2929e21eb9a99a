#pragma once
// Which image pairs to match, for video keyframes (paper section 3.4.1 matches image pairs; on
// a survey of thousands of keyframes exhaustive matching is quadratic, so):
//  * exhaustive when the survey has at most `exhaustive_max_images` images;
//  * sequential: each keyframe with the next `sequential_window` keyframes of the same camera
//    (index.csv order);
//  * cross-camera: keyframes of different cameras near in time (|dt| <= cross_camera_max_dt_s,
//    by sim_time_s, else camera_time_s; camera clocks are not synchronised, hence also:)
//  * loop closures and cross-camera by appearance: for each image the `loop_top_k` most similar
//    images by global descriptor (vocabulary.h) that are not already its sequential neighbours
//    (at least `loop_min_separation` keyframes apart in one camera), with a similarity of at
//    least `loop_min_score` times the image's best; when the vehicle's navigation gives the
//    images positions, only among images at most `loop_max_distance_m` apart (look-alike
//    surfaces far apart, e.g. a repeated texture, give geometrically consistent false pairs
//    that verification cannot reject and that attach parts of a model in the wrong place).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/features/match_store.h"

namespace auv::recon::features {

struct PairSelectionOptions {
  /// At most this many images: every pair is matched.
  int exhaustive_max_images = 50;
  /// Keyframes after each keyframe of the same camera matched with it.
  int sequential_window = 6;
  /// Cross-camera pairs by time: at most this far apart, s (0: none by time).
  double cross_camera_max_dt_s = 2.0;
  /// Most similar images matched per image by global descriptor (0: no appearance pairs).
  int loop_top_k = 5;
  /// Same-camera keyframes closer than this in index order are not loop candidates.
  int loop_min_separation = 10;
  /// Appearance candidates need a similarity >= this fraction of the image's best one.
  double loop_min_score = 0.5;
  /// Appearance candidates: at most this far apart by navigation position, m (images without
  /// a position are not limited; 0: no limit). Two keyframes can only share a view when the
  /// vehicle was within about twice the cameras' range; the margin covers navigation drift.
  double loop_max_distance_m = 10.0;
  /// Visual words of the vocabulary trained on the survey's descriptors (vocabulary.h).
  int vocabulary_words = 1024;

  void check() const;
};

/// What pair selection knows of an image.
struct PairImage {
  std::string name;  ///< "<camera>/<file>.png"
  std::string camera;
  int sequence = 0;  ///< position in its camera's keyframe order
  double time_s = std::numeric_limits<double>::quiet_NaN();  ///< NaN: unknown
  bool has_position = false;  ///< the navigation gives the vehicle's position at time_s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< m, navigation frame
};

struct CandidatePair {
  int index1 = 0, index2 = 0;  ///< into the image list, index1 < index2
  PairSource source = PairSource::SEQUENTIAL;
  /// Appearance similarity of the two images (NaN: no similarity was given).
  float similarity = std::numeric_limits<float>::quiet_NaN();
};

/// Candidate pairs, each once (first source wins: exhaustive, sequential, cross-camera, loop),
/// sorted by (index1, index2). `similarity`: n x n CV_32F global-descriptor similarity
/// (larger: more alike), or empty for no appearance pairs. Throws std::invalid_argument when
/// `similarity` has the wrong size.
std::vector<CandidatePair> selectPairs(const std::vector<PairImage>& images,
                                       const cv::Mat& similarity,
                                       const PairSelectionOptions& options);

}  // namespace auv::recon::features
