#pragma once
// Which ground-truth frame each survey image is. The sparse model names an image
// "<camera>/<file>.png" (relative to corrected/); keyframes/<camera>/index.csv gives the video
// and frame of that file; the simulator names its ground-truth frames "<video>#<frame>".

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "auv/recon/evaluate/alignment.h"
#include "auv/recon/evaluate/ground_truth.h"
#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::evaluate {

/// A keyframe of the survey: its file and the video frame it came from.
struct KeyframeSource {
  std::string camera;  ///< camera folder
  std::string file;    ///< file name in keyframes/<camera>/ (and corrected/<camera>/)
  std::string video;   ///< video file (or stem) of recordings/<camera>/
  int64_t frame = 0;   ///< frame in the video, from 0
  std::string key() const { return frameKey(video, frame); }
};

/// Every keyframe of `keyframes_folder`/<camera>/index.csv (header with at least the columns
/// file, video, frame). A camera folder without index.csv is read from its PNG names
/// "<video stem>_<frame>.png". Throws StageError("evaluate", ...) naming the file and line of
/// a malformed index. Cameras map to their keyframes in file order.
std::map<std::string, std::vector<KeyframeSource>> readKeyframeSources(
    const std::filesystem::path& keyframes_folder);

/// "<video stem>_<digits>.png" -> (stem, frame); false when the name is not of that form.
bool parseKeyframeName(const std::string& file, std::string& video_stem, int64_t& frame);

struct MatchedImage {
  uint32_t image_id = 0;  ///< id in the reconstruction
  std::string name;       ///< "<camera>/<file>"
  const GroundTruthFrame* truth = nullptr;
};

struct ImageMatching {
  std::vector<MatchedImage> matched;
  std::vector<std::string> unmatched;  ///< image names with no ground-truth frame
};

/// Pairs the registered images of `reconstruction` with ground-truth frames through
/// `sources` (by "<camera>/<file>"); names not in the sources are parsed as keyframe names.
ImageMatching matchImages(const scene::Reconstruction& reconstruction,
                          const std::map<std::string, std::vector<KeyframeSource>>& sources,
                          const GroundTruth& truth);

/// The poses of the matched images in the reconstruction and in the truth, for alignToTruth().
std::vector<PosePair> posePairs(const ImageMatching& matching,
                                const scene::Reconstruction& reconstruction);

}  // namespace auv::recon::evaluate
