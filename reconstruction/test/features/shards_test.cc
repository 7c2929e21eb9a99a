// Sharded features and matching (cluster/README.md): the shards' merge writes the same files as
// the whole run, on any number of shards, and refuses to merge when a shard is missing.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include <gtest/gtest.h>

#include "../support/folder_files.h"
#include "../support/quarter_sceaux.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"

namespace auv::recon::features {
namespace {

namespace fs = std::filesystem;

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_shards_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

using test_support::filesOf;

TEST(FeatureShards, MergedShardsEqualTheWholeRunOnAnyNumberOfShards) {
  const fs::path root = freshFolder("equal");
  const Survey survey(root);
  if (!test_support::quarterSceaux(survey)) GTEST_SKIP() << "Sceaux castle data absent";
  FeaturesStageOptions options;
  options.threads = 1;
  const FeaturesStageResult whole = runFeaturesStage(survey, options);
  const auto expected = filesOf(root / "features");
  ASSERT_EQ(expected.size(), whole.images + 1);  // a .sift per image and index.csv

  for (int count : {1, 3, static_cast<int>(whole.images) + 2}) {  // more shards than images too
    SCOPED_TRACE(count);
    fs::remove_all(root / "features");
    size_t images = 0;
    for (int index = 0; index < count; ++index) {
      images += runFeaturesShard(survey, options, {index, count});
    }
    EXPECT_EQ(images, whole.images);
    EXPECT_FALSE(fs::exists(root / "features"));  // shards write only their own folders
    const FeaturesStageResult merged = mergeFeaturesShards(survey, options, count);
    EXPECT_EQ(merged.features, whole.features);
    EXPECT_EQ(filesOf(root / "features"), expected);
    EXPECT_FALSE(fs::exists(root / ".shards" / "features"));  // cleaned up after the merge
  }
  fs::remove_all(root);
}

TEST(FeatureShards, AMissingShardIsNamedAndTheEarlierOutputStays) {
  const fs::path root = freshFolder("missing");
  const Survey survey(root);
  if (!test_support::quarterSceaux(survey)) GTEST_SKIP() << "Sceaux castle data absent";
  FeaturesStageOptions options;
  options.threads = 1;
  runFeaturesStage(survey, options);
  const auto before = filesOf(root / "features");
  runFeaturesShard(survey, options, {0, 2});
  try {
    mergeFeaturesShards(survey, options, 2);
    FAIL() << "merged without shard 1";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("shard 1 of 2 has not run"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--shard 1/2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(filesOf(root / "features"), before);
  EXPECT_THROW(runFeaturesShard(survey, options, {2, 2}), std::invalid_argument);
  fs::remove_all(root);
}

TEST(MatchShards, MergedShardsEqualTheWholeRunOnAnyNumberOfShards) {
  const fs::path root = freshFolder("match");
  const Survey survey(root);
  if (!test_support::quarterSceaux(survey)) GTEST_SKIP() << "Sceaux castle data absent";
  FeaturesStageOptions features;
  features.threads = 1;
  runFeaturesStage(survey, features);
  MatchStageOptions options;
  options.threads = 1;
  const MatchStageResult whole = runMatchStage(survey, options);
  const fs::path matches = root / "features" / "matches";
  const auto expected = filesOf(matches);
  ASSERT_EQ(expected.size(), 2u);  // pairs.bin, pairs.csv
  const int pairs = static_cast<int>(whole.candidate_pairs);
  for (int count : {3, pairs + 3}) {  // more shards than pairs too
    SCOPED_TRACE(count);
    fs::remove_all(matches);
    size_t matched = 0;
    for (int index = 0; index < count; ++index) {
      matched += runMatchShard(survey, options, {index, count});
    }
    EXPECT_EQ(matched, whole.candidate_pairs);
    const MatchStageResult merged = mergeMatchShards(survey, options, count);
    EXPECT_EQ(merged.verified_pairs, whole.verified_pairs);
    EXPECT_EQ(merged.verified_matches, whole.verified_matches);
    EXPECT_EQ(filesOf(matches), expected);
    EXPECT_FALSE(fs::exists(root / ".shards" / "match"));
  }
  // Shards of other options, of another plan or of other features are refused, naming them;
  // the merge reads the shards' plan instead of planning again, so it must notice each.
  const auto expectRefused = [&](const std::string& why) {
    try {
      mergeMatchShards(survey, options, 2);
      ADD_FAILURE() << "merged, expected: " << why;
    } catch (const StageError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  MatchStageOptions other = options;
  other.pairs.exhaustive_max_images = 2;  // sequential pairs: fewer candidates
  other.pairs.sequential_window = 1;
  runMatchShard(survey, options, {0, 2});
  runMatchShard(survey, other, {1, 2});
  expectRefused("shard 1 of 2 matched another plan than shard 0");
  MatchStageOptions stricter = options;  // the same candidates, another verification
  stricter.verification.min_inliers += 5;
  runMatchShard(survey, stricter, {0, 2});
  runMatchShard(survey, stricter, {1, 2});
  expectRefused("shard 0 of 2 ran with other match options than the merge");
  runMatchShard(survey, options, {0, 2});
  runMatchShard(survey, options, {1, 2});
  std::ofstream(root / "features" / "index.csv", std::ios::app) << "\n";  // features re-run since
  expectRefused("shard 0 of 2 matched other features than");
  EXPECT_EQ(filesOf(matches), expected);
  fs::remove_all(root);
}

}  // namespace
}  // namespace auv::recon::features
