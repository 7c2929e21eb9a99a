#include "auv/recon/features/features_stage.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/common/threads.h"
#include "auv/recon/masks/mask.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr const char* kStage = "features";

int threadCount(int requested) {
  if (requested > 0) return requested;
  return defaultThreadCount();
}

}  // namespace

void FeaturesStageOptions::check() const {
  sift.check();
  AUV_RECON_CHECK_OPTION(threads >= 0, threads, "must be >= 0 (0: all cores)");
}

void FeaturesStageOptions::bind(OptionSet& set) {
  set.add("max_features", &sift.max_features, "most SIFT keypoints per image (0: all)");
  set.add("keep", &sift.keep,
          "which keypoints max_features keeps: largest (coarsest scales first) or strongest");
  set.add("max_features_megapixels", &sift.max_features_megapixels,
          "MP: max_features holds up to this image size, larger images keep proportionally more "
          "(0: fixed)");
  set.add("contrast_threshold", &sift.contrast_threshold,
          "SIFT DoG contrast threshold (OpenCV's default 0.04 is too high underwater)");
  set.add("edge_threshold", &sift.edge_threshold, "SIFT edge response threshold");
  set.add("sigma", &sift.sigma, "px: Gaussian sigma of the first octave");
  set.add("octave_layers", &sift.octave_layers, "SIFT scales per octave");
  set.add("max_image_size", &sift.max_image_size,
          "px: detect on images downscaled to this larger side (0: full size)");
  set.add("root_sift", &sift.root_sift, "RootSIFT descriptors (else plain SIFT)");
  set.add("camera", &cameras, "only this camera (repeatable; default all)");
  set.add("threads", &threads, "images extracted at once (0: all cores)");
}

namespace {

struct Job {
  std::string camera;
  fs::path image;
};

/// The cameras and images of a run, sorted by camera, then file name: the index order.
std::vector<Job> listJobs(const Survey& survey, const FeaturesStageOptions& options,
                          std::vector<std::string>& cameras) {
  Survey::requireExists(survey.corrected(), kStage, "correct");
  cameras = Survey::cameraFolders(survey.corrected(), kStage);
  if (!options.cameras.empty()) {
    for (const std::string& wanted : options.cameras) {
      if (std::find(cameras.begin(), cameras.end(), wanted) == cameras.end()) {
        throw StageError(kStage,
                         "camera '" + wanted + "' has no folder in " + survey.corrected().string());
      }
    }
    cameras = options.cameras;
    std::sort(cameras.begin(), cameras.end());
  }
  std::vector<Job> jobs;
  for (const std::string& camera : cameras) {
    for (const fs::path& file :
         listFiles(survey.corrected() / camera, {".png", ".jpg", ".jpeg", ".tif", ".tiff"})) {
      jobs.push_back({camera, file});
    }
  }
  if (jobs.empty()) {
    throw StageError(
        kStage, "no images (.png/.jpg) in the camera folders of " + survey.corrected().string());
  }
  return jobs;
}

/// The features of `jobs`, written into `folder` (camera sub-folders); the index entries in job
/// order. `masked` counts the images with a mask, `threads_used` the threads.
std::vector<FeatureIndexEntry> extract(const Survey& survey, const FeaturesStageOptions& options,
                                       const std::vector<std::string>& cameras,
                                       const std::vector<Job>& jobs, const fs::path& folder,
                                       size_t& masked, int& threads_used) {
  // Masks (masks/mask.h): no keypoint on a burned-in overlay or the vehicle's own parts.
  std::map<std::string, std::unique_ptr<masks::CameraMasks>> camera_masks;
  for (const std::string& camera : cameras) {
    camera_masks[camera] = std::make_unique<masks::CameraMasks>(survey, camera, kStage);
    fs::create_directories(folder / camera);
  }
  std::atomic<size_t> masked_images{0};
  std::vector<FeatureIndexEntry> entries(jobs.size());
  Progress progress("features", "images", jobs.size());
  std::mutex error_mutex;
  std::string first_error;
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next++; i < jobs.size(); i = next++) {
      {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error.empty()) return;
      }
      const Job& job = jobs[i];
      try {
        const cv::Mat image = cv::imread(job.image.string(), cv::IMREAD_COLOR);
        if (image.empty()) {
          throw std::runtime_error(job.image.string() +
                                   ": cannot read the image (missing, "
                                   "truncated or not an image)");
        }
        const std::string name = job.camera + "/" + job.image.filename().string();
        const cv::Mat mask =
            camera_masks.at(job.camera)->forImage(job.image.filename().string(), image.size());
        if (!mask.empty()) ++masked_images;
        const ImageFeatures features = extractSift(image, name, options.sift, mask);
        FeatureIndexEntry& e = entries[i];
        e.image = name;
        e.camera = job.camera;
        e.width = features.width;
        e.height = features.height;
        e.count = features.size();
        e.file = fs::path(job.camera) / (job.image.stem().string() + ".sift");
        writeImageFeatures(folder / e.file, features);
      } catch (const std::exception& error) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (first_error.empty()) first_error = error.what();
        return;
      }
      progress.advance();
    }
  };
  threads_used = std::min<int>(threadCount(options.threads), static_cast<int>(jobs.size()));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads_used; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  progress.finish();
  if (!first_error.empty()) throw StageError(kStage, first_error);
  masked = masked_images.load();
  return entries;
}

/// The result of `entries` and the stage's section of report.json.
FeaturesStageResult finish(const Survey& survey, const FeaturesStageOptions& options,
                           const std::vector<FeatureIndexEntry>& entries, size_t masked,
                           double seconds, int threads, int shards) {
  FeaturesStageResult summary;
  summary.images = entries.size();
  summary.masked_images = masked;
  summary.min_features = entries.front().count;
  for (const FeatureIndexEntry& e : entries) {
    summary.features += e.count;
    summary.min_features = std::min(summary.min_features, e.count);
    summary.max_features = std::max(summary.max_features, e.count);
  }
  summary.seconds = seconds;
  nlohmann::json report = {{"images", summary.images},
                           {"features", summary.features},
                           {"features_per_image",
                            {{"min", summary.min_features},
                             {"mean", static_cast<double>(summary.features) / summary.images},
                             {"max", summary.max_features}}},
                           {"masked_images", masked},
                           {"seconds", summary.seconds},
                           {"threads", threads},
                           {"options",
                            {{"max_features", options.sift.max_features},
                             {"keep", options.sift.keep},
                             {"max_features_megapixels", options.sift.max_features_megapixels},
                             {"contrast_threshold", options.sift.contrast_threshold},
                             {"edge_threshold", options.sift.edge_threshold},
                             {"sigma", options.sift.sigma},
                             {"octave_layers", options.sift.octave_layers},
                             {"max_image_size", options.sift.max_image_size},
                             {"root_sift", options.sift.root_sift}}}};
  if (shards > 1) report["shards"] = shards;
  updateReport(survey.report(), kStage, report);
  return summary;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

FeaturesStageResult runFeaturesStage(const Survey& survey, const FeaturesStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> cameras;
  const std::vector<Job> jobs = listJobs(survey, options, cameras);
  StagedOutput output(survey.root() / "features");
  size_t masked = 0;
  int threads = 1;
  const std::vector<FeatureIndexEntry> entries =
      extract(survey, options, cameras, jobs, output.path(), masked, threads);
  writeFeatureIndex(output.path() / "index.csv", entries);
  output.commit();
  return finish(survey, options, entries, masked, secondsSince(start), threads, 1);
}

size_t runFeaturesShard(const Survey& survey, const FeaturesStageOptions& options, Shard shard) {
  options.check();
  shard.check();
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> cameras;
  const std::vector<Job> all = listJobs(survey, options, cameras);
  std::vector<Job> mine;  // every count-th image: shards of even work for images of one size
  for (size_t i = static_cast<size_t>(shard.index); i < all.size(); i += shard.count) {
    mine.push_back(all[i]);
  }
  StagedOutput output(shardFolder(survey, kStage, shard));
  size_t masked = 0;
  int threads = 1;
  const std::vector<FeatureIndexEntry> entries =
      mine.empty() ? std::vector<FeatureIndexEntry>{}
                   : extract(survey, options, cameras, mine, output.path(), masked, threads);
  writeFeatureIndex(output.path() / "index.csv", entries);
  writeFileAtomically(output.path() / "shard.json", nlohmann::json{{"masked_images", masked},
                                                                   {"seconds", secondsSince(start)},
                                                                   {"threads", threads}}
                                                        .dump());
  output.commit();
  return entries.size();
}

FeaturesStageResult mergeFeaturesShards(const Survey& survey, const FeaturesStageOptions& options,
                                        int count) {
  options.check();
  std::vector<std::string> cameras;
  const std::vector<Job> all = listJobs(survey, options, cameras);
  std::map<std::string, std::pair<FeatureIndexEntry, fs::path>> found;  // image -> (entry, folder)
  size_t masked = 0;
  double seconds = 0;
  int threads = 1;
  for (int index = 0; index < count; ++index) {
    const fs::path folder = shardFolder(survey, kStage, {index, count});
    const std::string rerun = "(`auv recon run " + survey.root().string() +
                              " --from features --to features --shard " + std::to_string(index) +
                              "/" + std::to_string(count) + "`)";
    if (!fs::exists(folder / "shard.json")) {
      throw StageError(kStage, "shard " + std::to_string(index) + " of " + std::to_string(count) +
                                   " has not run " + rerun);
    }
    const FeatureStore store(folder);
    for (const FeatureIndexEntry& e : store.images()) found[e.image] = {e, folder};
    std::ifstream in(folder / "shard.json");
    const nlohmann::json shard_report = nlohmann::json::parse(in, nullptr, false);
    masked += shard_report.value("masked_images", size_t{0});
    seconds += shard_report.value("seconds", 0.0);
    threads = std::max(threads, shard_report.value("threads", 1));
  }
  StagedOutput output(survey.root() / "features");
  std::vector<FeatureIndexEntry> entries;
  for (const Job& job : all) {
    const std::string name = job.camera + "/" + job.image.filename().string();
    const auto it = found.find(name);
    if (it == found.end()) {
      throw StageError(kStage, "no shard of " + std::to_string(count) + " holds " + name +
                                   " (corrected/ changed since the shards ran? run them again)");
    }
    const FeatureIndexEntry& e = it->second.first;
    fs::create_directories((output.path() / e.file).parent_path());
    fs::copy_file(it->second.second / e.file, output.path() / e.file);
    entries.push_back(e);
  }
  writeFeatureIndex(output.path() / "index.csv", entries);
  output.commit();
  fs::remove_all(survey.root() / ".shards" / kStage);
  return finish(survey, options, entries, masked, seconds, threads, count);
}

namespace {

StageReport reportOf(const Survey& survey, const FeaturesStageResult& result) {
  std::ostringstream line;
  line << "features: " << result.images << " images, " << result.features << " keypoints ("
       << result.min_features << "-" << result.max_features << " per image"
       << (result.masked_images ? ", " + std::to_string(result.masked_images) + " masked" : "")
       << ") in " << result.seconds << " s -> " << (survey.root() / "features").string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary =
      std::to_string(result.images) + " images, " + std::to_string(result.features) + " keypoints";
  return report;
}

}  // namespace

StageReport FeaturesStage::runWith(const Survey& survey,
                                   const FeaturesStageOptions& options) const {
  return reportOf(survey, runFeaturesStage(survey, options));
}

StageReport FeaturesStage::runShardWith(const Survey& survey, const FeaturesStageOptions& options,
                                        Shard shard) const {
  return shardReport("features", shard,
                     std::to_string(runFeaturesShard(survey, options, shard)) + " images");
}

StageReport FeaturesStage::mergeShardsWith(const Survey& survey,
                                           const FeaturesStageOptions& options, int count) const {
  return mergedReport(reportOf(survey, mergeFeaturesShards(survey, options, count)), count);
}

}  // namespace auv::recon::features
