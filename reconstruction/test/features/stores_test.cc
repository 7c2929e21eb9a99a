// The feature and match files round-trip, and damaged files are reported by name.
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/match_store.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_h2_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

ImageFeatures randomFeatures(const std::string& name, int count, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  ImageFeatures f;
  f.image = name;
  f.width = 640;
  f.height = 480;
  for (int i = 0; i < count; ++i) {
    Keypoint k;
    k.x = 639 * unit(random);
    k.y = 479 * unit(random);
    k.size = 1 + 30 * unit(random);
    k.angle = 360 * unit(random);
    k.response = unit(random);
    k.rgb = {static_cast<uint8_t>(i), static_cast<uint8_t>(2 * i), 7};
    f.keypoints.push_back(k);
  }
  f.descriptors.create(count, 128, CV_8U);
  if (count > 0) cv::randu(f.descriptors, 0, 256);
  return f;
}

void truncateFile(const fs::path& file, size_t keep) {
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), keep);
}

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(FeatureStore, ImageFeaturesRoundTrip) {
  const fs::path folder = freshFolder("sift_roundtrip");
  const ImageFeatures written = randomFeatures("left/a.png", 300, 1);
  writeImageFeatures(folder / "a.sift", written);
  const ImageFeatures read = readImageFeatures(folder / "a.sift");
  ASSERT_EQ(read.size(), written.size());
  EXPECT_EQ(read.width, 640);
  EXPECT_EQ(read.height, 480);
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read.keypoints[i].x, written.keypoints[i].x);
    EXPECT_EQ(read.keypoints[i].y, written.keypoints[i].y);
    EXPECT_EQ(read.keypoints[i].size, written.keypoints[i].size);
    EXPECT_EQ(read.keypoints[i].angle, written.keypoints[i].angle);
    EXPECT_EQ(read.keypoints[i].response, written.keypoints[i].response);
    EXPECT_EQ(read.keypoints[i].rgb, written.keypoints[i].rgb);
  }
  EXPECT_EQ(cv::norm(read.descriptors, written.descriptors, cv::NORM_INF), 0);
  // Empty features round-trip too.
  writeImageFeatures(folder / "empty.sift", randomFeatures("e.png", 0, 2));
  EXPECT_EQ(readImageFeatures(folder / "empty.sift").size(), 0u);
  fs::remove_all(folder);
}

TEST(FeatureStore, DamagedFilesAreNamed) {
  const fs::path folder = freshFolder("sift_damaged");
  writeImageFeatures(folder / "a.sift", randomFeatures("a.png", 50, 3));
  truncateFile(folder / "a.sift", 1000);
  const std::string truncated = errorOf([&] { readImageFeatures(folder / "a.sift"); });
  EXPECT_NE(truncated.find((folder / "a.sift").string()), std::string::npos) << truncated;
  EXPECT_NE(truncated.find("truncated"), std::string::npos) << truncated;
  std::ofstream(folder / "b.sift") << "this is not a feature file";
  const std::string magic = errorOf([&] { readImageFeatures(folder / "b.sift"); });
  EXPECT_NE(magic.find("b.sift: not a .sift"), std::string::npos) << magic;
  const std::string missing = errorOf([&] { readImageFeatures(folder / "none.sift"); });
  EXPECT_NE(missing.find("none.sift: cannot open"), std::string::npos) << missing;
  fs::remove_all(folder);
}

TEST(FeatureStore, IndexRoundTripAndLookup) {
  const fs::path folder = freshFolder("store");
  fs::create_directories(folder / "left");
  std::vector<FeatureIndexEntry> entries;
  for (int i = 0; i < 3; ++i) {
    const std::string stem = "left_0001_00000" + std::to_string(i);
    const ImageFeatures f = randomFeatures("left/" + stem + ".png", 10 + i, 10 + i);
    writeImageFeatures(folder / "left" / (stem + ".sift"), f);
    entries.push_back(
        {f.image, "left", f.width, f.height, f.size(), fs::path("left") / (stem + ".sift")});
  }
  writeFeatureIndex(folder / "index.csv", entries);
  const FeatureStore store(folder);
  ASSERT_EQ(store.images().size(), 3u);
  EXPECT_TRUE(store.contains("left/left_0001_000001.png"));
  const ImageFeatures f = store.read("left/left_0001_000002.png");
  EXPECT_EQ(f.image, "left/left_0001_000002.png");
  EXPECT_EQ(f.size(), 12u);
  EXPECT_EQ(store.entry("left/left_0001_000000.png").count, 10u);
  EXPECT_THROW(store.read("left/unknown.png"), std::out_of_range);
  fs::remove_all(folder);
}

TEST(FeatureStore, MissingOrMalformedIndexIsNamed) {
  const fs::path folder = freshFolder("store_bad");
  try {
    FeatureStore store(folder);
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("index.csv not found"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("auv recon features"), std::string::npos) << e.what();
  }
  std::ofstream(folder / "index.csv") << "image,camera,width,height,features,file\n"
                                      << "left/a.png,left,640,x,10,left/a.sift\n";
  const std::string malformed = errorOf([&] { FeatureStore store(folder); });
  EXPECT_NE(malformed.find("index.csv: line 2"), std::string::npos) << malformed;
  fs::remove_all(folder);
}

std::vector<VerifiedPair> somePairs() {
  std::vector<VerifiedPair> pairs(3);
  for (size_t i = 0; i < pairs.size(); ++i) {
    VerifiedPair& p = pairs[i];
    p.image1 = "left/a" + std::to_string(i) + ".png";
    p.image2 = "right/b" + std::to_string(i) + ".png";
    p.kind = static_cast<GeometryKind>(i % 3);
    p.source = static_cast<PairSource>(i % 4);
    p.model = Eigen::Matrix3d::Random();
    p.log10_nfa = -100.5 - i;
    p.threshold_px = 1.25 + i;
    p.putative = 500 + static_cast<uint32_t>(i);
    p.homography_inliers = 42;
    for (uint32_t k = 0; k < 40 + i; ++k) p.inliers.emplace_back(k, 3 * k + 1);
  }
  return pairs;
}

TEST(MatchStore, VerifiedPairsRoundTrip) {
  const fs::path folder = freshFolder("pairs");
  const std::vector<VerifiedPair> written = somePairs();
  writeVerifiedPairs(folder / "pairs.bin", written);
  const std::vector<VerifiedPair> read = readVerifiedPairs(folder / "pairs.bin");
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].image1, written[i].image1);
    EXPECT_EQ(read[i].image2, written[i].image2);
    EXPECT_EQ(read[i].kind, written[i].kind);
    EXPECT_EQ(read[i].source, written[i].source);
    EXPECT_EQ(read[i].model, written[i].model);
    EXPECT_EQ(read[i].log10_nfa, written[i].log10_nfa);
    EXPECT_EQ(read[i].threshold_px, written[i].threshold_px);
    EXPECT_EQ(read[i].putative, written[i].putative);
    EXPECT_EQ(read[i].homography_inliers, written[i].homography_inliers);
    EXPECT_EQ(read[i].inliers, written[i].inliers);
  }
  EXPECT_EQ(geometryKindName(GeometryKind::ESSENTIAL), "essential");
  EXPECT_EQ(pairSourceName(PairSource::LOOP), "loop");
  EXPECT_EQ(verifiedPairsFile("f"), fs::path("f/matches/pairs.bin"));
  fs::remove_all(folder);
}

TEST(MatchStore, DamagedFilesAreNamed) {
  const fs::path folder = freshFolder("pairs_bad");
  writeVerifiedPairs(folder / "pairs.bin", somePairs());
  truncateFile(folder / "pairs.bin", 300);
  const std::string truncated = errorOf([&] { readVerifiedPairs(folder / "pairs.bin"); });
  EXPECT_NE(truncated.find("pairs.bin"), std::string::npos) << truncated;
  EXPECT_NE(truncated.find("truncated"), std::string::npos) << truncated;
  std::ofstream(folder / "other.bin") << "AUVSIFT1 something else";
  const std::string magic = errorOf([&] { readVerifiedPairs(folder / "other.bin"); });
  EXPECT_NE(magic.find("other.bin: not a pairs file"), std::string::npos) << magic;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace auv::recon::features
