#pragma once
// `auv recon features <survey>`: SIFT (sift_extractor.h) of every image of corrected/<camera>/
// -> features/ (feature_store.h) and the `features` section of report.json.

#include <filesystem>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/features/sift_extractor.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::features {

struct FeaturesStageOptions {
  SiftOptions sift;
  /// Only these cameras (folders of corrected/); empty: all.
  std::vector<std::string> cameras;
  /// Images extracted at once (0: the machine's cores); memory grows with it.
  int threads = 0;

  void check() const;
  /// Binds the fields to flags / the `features:` section of a config file.
  void bind(OptionSet& set);
};

struct FeaturesStageResult {
  size_t images = 0;
  size_t features = 0;  ///< total over the images
  size_t min_features = 0, max_features = 0;
  size_t masked_images = 0;  ///< images with a mask (masks/mask.h)
  double seconds = 0;
};

/// `auv recon features <survey>`: extracts every image of corrected/<camera>/ into
/// <survey>/features/ (StagedOutput: a failure leaves an earlier features/ intact), with a
/// progress bar, and writes the `features` section of report.json. Throws StageError naming the
/// missing corrected/ folder or the unreadable image.
FeaturesStageResult runFeaturesStage(const Survey& survey, const FeaturesStageOptions& options);

/// Shard `shard` of a sharded run (cluster/README.md): every shard.count-th image from
/// shard.index on, into shardFolder(survey, "features", shard) (its own index.csv and
/// shard.json). Returns the images extracted.
size_t runFeaturesShard(const Survey& survey, const FeaturesStageOptions& options, Shard shard);

/// features/ from the `count` shards' folders, the same files as runFeaturesStage writes; the
/// shards' folders are removed after. Throws StageError naming a shard that has not run or an
/// image no shard holds.
FeaturesStageResult mergeFeaturesShards(const Survey& survey, const FeaturesStageOptions& options,
                                        int count);

/// The `features` stage (common/stage.h): `auv recon features` and a step of `auv recon run`.
class FeaturesStage final : public StageWith<FeaturesStageOptions> {
 public:
  std::string name() const override { return "features"; }
  std::string usage() const override { return "<survey>   SIFT features of the corrected images"; }
  std::string surveyHelp() const override {
    return "survey folder (reads corrected/, writes features/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.corrected()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.root() / "features" / "index.csv"};
  }
  StageReport runWith(const Survey& survey, const FeaturesStageOptions& options) const override;
  bool shardable() const override { return true; }
  StageReport runShardWith(const Survey& survey, const FeaturesStageOptions& options,
                           Shard shard) const override;
  StageReport mergeShardsWith(const Survey& survey, const FeaturesStageOptions& options,
                              int count) const override;
};

}  // namespace auv::recon::features
