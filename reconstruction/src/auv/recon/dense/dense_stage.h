#pragma once
// `auv recon dense`: sparse model + undistorted images -> depth maps and a fused, coloured,
// oriented point cloud (docs/paper.md §3.5). See README.md beside this file.
//
//   dense/
//     depth_maps/<image name without extension>.depth.bin   per master (depth_map.h format)
//     neighbours.csv                                        the images each master was matched with
//     fused.ply                                             xyz, normals, rgb (binary PLY)
//     fused_views.bin                                       contributing image ids per point

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/dense/fusion.h"
#include "auv/recon/dense/matcher.h"
#include "auv/recon/dense/neighbours.h"
#include "auv/recon/scene/reconstruction.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::dense {

struct DenseStageOptions {
  int max_image_size = 1024;      ///< px: longer image side depth maps are computed at (0: full)
  int min_registered_images = 2;  ///< fewer registered images in the model: StageError
  int min_points = 1000;          ///< a fused cloud with fewer points: StageError
  int image_cache = 12;           ///< images (and depth maps) kept in memory between masters
  bool keep_depth_maps = true;    ///< leave dense/depth_maps/ in the output
  NeighbourOptions neighbours;
  MatcherOptions matcher;
  FusionOptions fusion;

  /// Checks every field, the sub-stages' included.
  void check() const;
  nlohmann::json toJson() const;
  /// Binds the fields to flags / the `dense:` section of a config file.
  void bind(OptionSet& set);
};

/// Time and peak resident memory of a sub-stage.
struct SubStageFigures {
  double seconds = 0;      ///< wall clock
  double cpu_seconds = 0;  ///< process CPU time, all threads (less noisy on a shared machine)
  size_t peak_memory_bytes = 0;
};

struct DenseStageResult {
  size_t registered_images = 0;
  size_t masters = 0;              ///< images with neighbours and a depth range
  size_t depth_maps = 0;           ///< depth maps computed
  size_t depth_pixels = 0;         ///< valid depths over all maps
  size_t depths_fused = 0;         ///< depths considered by fusion (not already part of a point)
  size_t depths_inconsistent = 0;  ///< of these, dropped by the consistency check
  size_t points = 0;
  size_t masked_depth_maps = 0;  ///< depth maps cleared where their image's mask is 0
  int width = 0, height = 0;     ///< size of the first depth map, px
  SubStageFigures neighbours, matching, fusion, writing;
  double seconds = 0;

  nlohmann::json toJson() const;
};

/// The mask of an image (name as in the model, size of the image file): CV_8U, 0 where the
/// image must give no depth (masks/mask.h); empty when it has none.
using ImageMasks = std::function<cv::Mat(const std::string& name, cv::Size size)>;

/// Dense matching of `model` (PINHOLE cameras) with images under `image_folder` (the model's
/// image names are relative to it), written through a StagedOutput to `output_folder`.
/// Masked pixels (`masks`, optional) get no depth, hence no fused point.
/// Throws StageError("dense", ...) for too few registered images, no image to match or a
/// cloud below min_points (the previous `output_folder` then stays as it was).
DenseStageResult densify(const scene::Reconstruction& model,
                         const std::filesystem::path& image_folder,
                         const std::filesystem::path& output_folder,
                         const DenseStageOptions& options, const ImageMasks& masks = nullptr);

/// The survey's sparse/ and corrected/ -> dense/, and the "dense" section of report.json.
DenseStageResult runDenseStage(const Survey& survey, const DenseStageOptions& options);

/// Shard `shard` of a sharded run (cluster/README.md): the depth maps of every count-th master
/// (in the order the neighbour selection gives them) into shardFolder(survey, "dense", shard):
/// depth_maps/ and shard.json (its masters and figures). Returns the depth maps computed.
size_t runDenseShard(const Survey& survey, const DenseStageOptions& options, Shard shard);

/// dense/ from the `count` shards' depth maps: neighbours.csv, the fusion and every file
/// runDenseStage writes, the same bytes; the shards' folders are removed after. Throws
/// StageError naming a shard that has not run, lacks a depth map or ran on another sparse model
/// (the previous dense/ then stays as it was).
DenseStageResult mergeDenseShards(const Survey& survey, const DenseStageOptions& options,
                                  int count);

/// The `dense` stage (common/stage.h): `auv recon dense` and a step of `auv recon run`.
class DenseStage final : public StageWith<DenseStageOptions> {
 public:
  std::string name() const override { return "dense"; }
  std::string usage() const override {
    return "<survey>   depth maps and the fused point cloud (dense/)";
  }
  std::string surveyHelp() const override { return "survey folder (reads sparse/ and corrected/)"; }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.sparse()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.dense()};
  }
  StageReport runWith(const Survey& survey, const DenseStageOptions& options) const override;
  bool shardable() const override { return true; }
  StageReport runShardWith(const Survey& survey, const DenseStageOptions& options,
                           Shard shard) const override;
  StageReport mergeShardsWith(const Survey& survey, const DenseStageOptions& options,
                              int count) const override;
};

}  // namespace auv::recon::dense
