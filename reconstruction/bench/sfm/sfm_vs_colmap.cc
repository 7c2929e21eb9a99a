// Benchmark (issue 6): our features + match + incremental SfM against COLMAP 3.8 (CPU:
// feature_extractor, a matcher, mapper) on the same undistorted images of a survey
// (corrected/<camera>/ + corrected/<camera>.yaml), in the same run: wall time per stage,
// images registered, points, mean track length, mean reprojection error (both models measured
// by the same code), and, with --truth (a simulator run's ground_truth/ folder), the camera
// position error after a similarity alignment to the true poses.
//
//   sfm_vs_colmap --survey S --work DIR --out bench_results/sfm_vs_colmap_<name>.json
//                 [--truth <run>/ground_truth] [--threads 2] [--skip-colmap] [--skip-ours]
//                 [--colmap-matcher exhaustive|sequential|vocab_tree] [--vocab-images 20]
//
// COLMAP's matchers (issue 24): exhaustive (every pair), sequential (each image with the next
// 10 of COLMAP's image order, which is camera by camera here, and quadratic overlap; no loop
// detection) and vocab_tree (a tree of 4096 words built on the survey's own descriptors with
// vocab_tree_builder, then the --vocab-images most similar images per image).
//
// The survey's features/, sparse/ are (re)written by our stages; COLMAP works in DIR/colmap.
// Goal (issue 6): our time <= 0.5x COLMAP's, error <= COLMAP's, registered >= COLMAP's.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <regex>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "auv/recon/common/survey.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/sfm/alignment.h"
#include "auv/recon/sfm/sfm_stage.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double timedSystem(const std::string& command, const fs::path& log) {
  const auto start = Clock::now();
  const int code = std::system((command + " >> '" + log.string() + "' 2>&1").c_str());
  if (code != 0) throw std::runtime_error("failed (" + std::to_string(code) + "): " + command);
  return since(start);
}

/// The first line `command` prints on stdout (empty when it fails).
std::string firstLine(const std::string& command) {
  std::string line;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[256];
    if (fgets(buffer, sizeof buffer, pipe) != nullptr) line = buffer;
    pclose(pipe);
  }
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  return line;
}

struct ModelFigures {
  size_t images = 0, points = 0;
  double track_length = 0, reprojection_px = 0;
  nlohmann::json pose_errors;
};

/// Survey image "<camera>/<video>_<frame 6 digits>.png" -> ground-truth NAME "<video>.mp4#<frame>".
std::string truthName(const std::string& image) {
  static const std::regex pattern(R"(([^/]+)/(.+)_(\d{6})\.[A-Za-z]+$)");
  std::smatch m;
  if (!std::regex_search(image, m, pattern)) return "";
  return m[2].str() + ".mp4#" + std::to_string(std::stoi(m[3].str()));
}

ModelFigures figures(const scene::Reconstruction& model,
                     const std::map<std::string, scene::Image>& truth_by_name) {
  ModelFigures f;
  f.images = model.images.size();
  f.points = model.points.size();
  f.track_length = model.meanTrackLength();
  f.reprojection_px = model.meanReprojectionError();
  if (!truth_by_name.empty()) {
    std::map<uint32_t, scene::Image> estimated, reference;
    for (const auto& [id, image] : model.images) {
      auto t = truth_by_name.find(truthName(image.name));
      if (t == truth_by_name.end()) continue;
      estimated[id] = image;
      reference[id] = t->second;
    }
    const auto e = auv::recon::sfm::poseErrorsAfterAlignment(estimated, reference);
    if (e) {
      f.pose_errors = {{"images", e->images},
                       {"mean_position_m", e->mean_position},
                       {"median_position_m", e->median_position},
                       {"max_position_m", e->max_position},
                       {"mean_rotation_deg", e->mean_rotation_deg}};
    }
  }
  return f;
}

}  // namespace

int benchMain(int argc, char** argv) {
  std::map<std::string, std::string> args;
  bool skip_colmap = false, skip_ours = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--skip-colmap") {
      skip_colmap = true;
    } else if (a == "--skip-ours") {
      skip_ours = true;
    } else if (a.rfind("--", 0) == 0 && i + 1 < argc) {
      args[a.substr(2)] = argv[++i];
    } else {
      std::cerr << "usage: sfm_vs_colmap --survey S --work DIR --out FILE.json [--truth DIR] "
                   "[--threads N] [--skip-colmap] [--skip-ours] [--colmap-matcher "
                   "exhaustive|sequential|vocab_tree] [--vocab-images N]\n";
      return 2;
    }
  }
  if (!args.count("survey") || !args.count("work") || !args.count("out")) {
    std::cerr << "sfm_vs_colmap: --survey, --work and --out are required\n";
    return 2;
  }
  const int threads = args.count("threads") ? std::stoi(args["threads"]) : 2;
  const std::string matcher = args.count("colmap-matcher") ? args["colmap-matcher"] : "exhaustive";
  if (matcher != "exhaustive" && matcher != "sequential" && matcher != "vocab_tree") {
    std::cerr << "sfm_vs_colmap: --colmap-matcher " << matcher
              << ": must be exhaustive, sequential or vocab_tree\n";
    return 2;
  }
  const std::string vocab_images = args.count("vocab-images") ? args["vocab-images"] : "20";
  const Survey survey(args["survey"]);
  const fs::path work = fs::absolute(args["work"]);
  fs::create_directories(work);
  nlohmann::json result = {{"survey", survey.root().string()}, {"threads", threads}};

  std::map<std::string, scene::Image> truth;
  if (args.count("truth")) {
    const fs::path truth_dir = args["truth"];
    if (fs::is_directory(truth_dir)) {
      for (const auto& entry : fs::directory_iterator(truth_dir)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("images_", 0) != 0 || entry.path().extension() != ".txt") continue;
        for (auto& [id, image] : scene::readColmapImages(entry.path())) truth[image.name] = image;
      }
    }
    if (truth.empty()) {  // a run's folder instead of its ground_truth/ measured nothing
      std::cerr << "sfm_vs_colmap: --truth " << truth_dir.string()
                << ": no images_*.txt poses there (give a simulator run's ground_truth/)\n";
      return 2;
    }
    std::cerr << "bench: " << truth.size() << " ground-truth poses\n";
  }

  // Ours: features, match, sfm (library entry points, as `auv recon run` calls them).
  if (!skip_ours) {
    features::FeaturesStageOptions extraction;
    extraction.threads = threads;
    features::MatchStageOptions matching;
    matching.threads = threads;
    sfm::SfmStageOptions mapping;
    mapping.threads = threads;
    auto start = Clock::now();
    features::runFeaturesStage(survey, extraction);
    const double t_features = since(start);
    start = Clock::now();
    features::runMatchStage(survey, matching);
    const double t_match = since(start);
    start = Clock::now();
    const sfm::SfmStageResult s = sfm::runSfmStage(survey, mapping);
    const double t_sfm = since(start);
    const ModelFigures f = figures(scene::readColmapText(survey.sparse()), truth);
    result["ours"] = {{"seconds_features", t_features},
                      {"seconds_match", t_match},
                      {"seconds_sfm", t_sfm},
                      {"seconds_total", t_features + t_match + t_sfm},
                      {"images_total", s.images_total},
                      {"images_registered", f.images},
                      {"points", f.points},
                      {"mean_track_length", f.track_length},
                      {"mean_reprojection_error_px", f.reprojection_px},
                      {"pose_errors", f.pose_errors}};
  }

  // COLMAP 3.8 on the same images and intrinsics: one feature_extractor run per camera folder
  // (its own PINHOLE parameters), exhaustive matching, mapper; the model converted to text.
  if (!skip_colmap) {
    const fs::path colmap = work / "colmap";
    fs::remove_all(colmap);
    fs::create_directories(colmap / "sparse");
    const fs::path log = colmap / "colmap.log", db = colmap / "database.db";
    double t_features = 0;
    for (const std::string& camera : Survey::cameraFolders(survey.corrected(), "bench")) {
      cv::FileStorage yaml((survey.corrected() / (camera + ".yaml")).string(),
                           cv::FileStorage::READ);
      cv::Mat k;
      yaml["camera_matrix"] >> k;
      k.convertTo(k, CV_64F);
      // COLMAP's principal point convention: +0.5 px.
      std::ostringstream params;
      params << std::setprecision(12) << k.at<double>(0, 0) << "," << k.at<double>(1, 1) << ","
             << k.at<double>(0, 2) + 0.5 << "," << k.at<double>(1, 2) + 0.5;
      std::ofstream list(colmap / (camera + ".list"));
      for (const auto& file :
           listFiles(survey.corrected() / camera, {".png", ".jpg", ".jpeg", ".tif", ".tiff"})) {
        list << camera << "/" << file.filename().string() << "\n";
      }
      list.close();
      t_features += timedSystem(
          "colmap feature_extractor --database_path '" + db.string() + "' --image_path '" +
              survey.corrected().string() + "' --image_list_path '" +
              (colmap / (camera + ".list")).string() +
              "' --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1"
              " --ImageReader.camera_params " +
              params.str() + " --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads " +
              std::to_string(threads),
          log);
    }
    const std::string common = " --database_path '" + db.string() +
                               "' --SiftMatching.use_gpu 0 --SiftMatching.num_threads " +
                               std::to_string(threads);
    double t_match = 0;
    if (matcher == "vocab_tree") {
      const fs::path tree = colmap / "vocab_tree.bin";
      t_match +=
          timedSystem("colmap vocab_tree_builder --database_path '" + db.string() +
                          "' --vocab_tree_path '" + tree.string() + "' --num_visual_words 4096",
                      log);
      t_match += timedSystem("colmap vocab_tree_matcher" + common +
                                 " --VocabTreeMatching.vocab_tree_path '" + tree.string() +
                                 "' --VocabTreeMatching.num_images " + vocab_images,
                             log);
    } else {
      t_match = timedSystem("colmap " + matcher + "_matcher" + common, log);
    }
    // Pairs matched and pairs with a verified two-view geometry (COLMAP's database).
    auto count = [&](const std::string& sql) {
      const std::string n = firstLine("sqlite3 '" + db.string() + "' '" + sql + "'");
      return n.empty() ? -1L : std::stol(n);
    };
    const long candidate_pairs = count("select count(*) from matches where rows > 0");
    const long verified_pairs = count("select count(*) from two_view_geometries where rows > 0");
    const double t_map = timedSystem("colmap mapper --database_path '" + db.string() +
                                         "' --image_path '" + survey.corrected().string() +
                                         "' --output_path '" + (colmap / "sparse").string() +
                                         "' --Mapper.num_threads " + std::to_string(threads),
                                     log);
    // The largest model (COLMAP may split the scene into several).
    fs::path best;
    size_t best_images = 0;
    for (const auto& entry : fs::directory_iterator(colmap / "sparse")) {
      if (!entry.is_directory()) continue;
      const fs::path text = colmap / ("text_" + entry.path().filename().string());
      fs::create_directories(text);
      timedSystem("colmap model_converter --input_path '" + entry.path().string() +
                      "' --output_path '" + text.string() + "' --output_type TXT",
                  log);
      const size_t n = scene::readColmapText(text).images.size();
      if (n > best_images) {
        best_images = n;
        best = text;
      }
    }
    ModelFigures f;
    if (!best.empty()) f = figures(scene::readColmapText(best), truth);
    result["colmap"] = {{"version", "3.8 (Debian, CPU)"},
                        {"matcher", matcher},
                        {"matched_pairs", candidate_pairs},
                        {"verified_pairs", verified_pairs},
                        {"seconds_features", t_features},
                        {"seconds_match", t_match},
                        {"seconds_sfm", t_map},
                        {"seconds_total", t_features + t_match + t_map},
                        {"models", std::distance(fs::directory_iterator(colmap / "sparse"),
                                                 fs::directory_iterator())},
                        {"images_registered", f.images},
                        {"points", f.points},
                        {"mean_track_length", f.track_length},
                        {"mean_reprojection_error_px", f.reprojection_px},
                        {"pose_errors", f.pose_errors}};
  }

  // Side by side.
  std::cout << std::fixed << std::setprecision(3);
  std::cout << "figure                         ours        COLMAP 3.8\n";
  auto row = [&](const std::string& label, const std::string& key) {
    std::cout << std::left << std::setw(28) << label << std::right << std::setw(10)
              << (result.contains("ours") ? result["ours"].value(key, 0.0) : 0.0);
    if (result.contains("colmap")) std::cout << std::setw(14) << result["colmap"].value(key, 0.0);
    std::cout << "\n";
  };
  row("features s", "seconds_features");
  row("matching s", "seconds_match");
  row("sfm s", "seconds_sfm");
  row("total s", "seconds_total");
  row("images registered", "images_registered");
  row("points", "points");
  row("mean track length", "mean_track_length");
  row("mean reprojection error px", "mean_reprojection_error_px");
  if (result.contains("colmap") && result.contains("ours")) {
    const double ratio = result["ours"]["seconds_total"].get<double>() /
                         result["colmap"]["seconds_total"].get<double>();
    result["time_ratio_ours_over_colmap"] = ratio;
    std::cout << "time ours / COLMAP: " << ratio << " (goal <= 0.5)\n";
  }
  if (!truth.empty()) {
    if (result.contains("ours")) {
      std::cout << "pose errors ours:   " << result["ours"]["pose_errors"].dump() << "\n";
    }
    if (result.contains("colmap")) {
      std::cout << "pose errors COLMAP: " << result["colmap"]["pose_errors"].dump() << "\n";
    }
  }
  fs::create_directories(fs::absolute(args["out"]).parent_path());
  std::ofstream(args["out"]) << result.dump(2) << "\n";
  std::cout << "results: " << args["out"] << std::endl;
  return 0;
}

int main(int argc, char** argv) {
  try {
    return benchMain(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "sfm_vs_colmap: " << error.what() << "\n";
    return 1;
  }
}
