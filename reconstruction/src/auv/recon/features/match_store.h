#pragma once
// Geometrically verified matches of image pairs (paper section 3.4.1): what SfM builds its
// tracks from.
//
//   <survey>/features/matches/
//     pairs.bin   every verified pair (format below)
//     pairs.csv   one line per candidate pair, for people: image1,image2,source,kind,
//                 putative,inliers,homography_inliers,log10_nfa,threshold_px,status,
//                 iterations,similarity
//
// `pairs.bin` (little-endian, README.md of this folder):
//   char[8] "AUVMATCH", uint32 version (1), uint32 pair count, then per pair:
//   uint16 length + bytes of image1; uint16 length + bytes of image2;
//   uint8 kind (GeometryKind); uint8 source (PairSource);
//   float64[9] model, row-major; float64 log10_nfa; float64 threshold_px;
//   uint32 putative; uint32 homography_inliers; uint32 inlier count n;
//   n x (uint32 index1, uint32 index2)      keypoint indices into image1's / image2's features

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::features {

/// The two-view model a pair was verified with.
enum class GeometryKind : uint8_t {
  ESSENTIAL =
      0,  ///< both cameras calibrated: x2n^T E x1n = 0, xn = K^-1 x (estimators/essential.h)
  FUNDAMENTAL = 1,  ///< otherwise: x2^T F x1 = 0 in px (estimators/fundamental.h)
  HOMOGRAPHY = 2,   ///< x2 ~ H x1 in px (estimators/homography.h)
};
std::string geometryKindName(GeometryKind kind);

/// Why the pair was a candidate (pair_selection.h).
enum class PairSource : uint8_t {
  EXHAUSTIVE = 0,    ///< small survey: every pair
  SEQUENTIAL = 1,    ///< neighbouring keyframes of one camera
  CROSS_CAMERA = 2,  ///< two cameras near in time
  LOOP = 3,          ///< similar by global descriptor (loop-closure candidate)
};
std::string pairSourceName(PairSource source);

/// Keypoint indices of one match: image1's keypoint `first`, image2's keypoint `second`.
using MatchIndices = std::pair<uint32_t, uint32_t>;

struct VerifiedPair {
  std::string image1, image2;  ///< "<camera>/<file>.png", image1 < image2
  GeometryKind kind = GeometryKind::ESSENTIAL;
  PairSource source = PairSource::EXHAUSTIVE;
  Eigen::Matrix3d model = Eigen::Matrix3d::Zero();  ///< maps image1 to image2 (see kind)
  double log10_nfa = 0;                             ///< AC-RANSAC's log10 NFA of the model (< 0)
  double threshold_px = 0;                          ///< AC-RANSAC's adaptive inlier threshold, px
  uint32_t putative = 0;                            ///< matches after the ratio and mutual tests
  /// Inliers of an AC-RANSAC homography on the same putative matches (0: none meaningful);
  /// a ratio homography_inliers / inliers near 1 means a planar scene or a pure rotation.
  /// With VerificationOptions::hopeless_exit, 0 also when fewer than min_inliers.
  uint32_t homography_inliers = 0;
  std::vector<MatchIndices> inliers;  ///< geometrically verified matches

  size_t numInliers() const { return inliers.size(); }
};

/// Writes pairs.bin atomically. Throws std::runtime_error naming the file.
void writeVerifiedPairs(const std::filesystem::path& pairs_bin,
                        const std::vector<VerifiedPair>& pairs);
/// Reads pairs.bin. Throws std::runtime_error naming the file when it is missing, truncated or
/// not a pairs file.
std::vector<VerifiedPair> readVerifiedPairs(const std::filesystem::path& pairs_bin);

/// `<features folder>/matches/pairs.bin` of a survey's features folder.
std::filesystem::path verifiedPairsFile(const std::filesystem::path& features_folder);

}  // namespace auv::recon::features
