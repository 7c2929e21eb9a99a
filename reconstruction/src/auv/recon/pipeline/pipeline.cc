#include "auv/recon/pipeline/pipeline.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <ostream>
#include <sstream>

#include "auv/recon/color/correct_stage.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/dense/dense_stage.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/features/sift_extractor.h"
#include "auv/recon/keyframes/stage.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/sfm/sfm_stage.h"
#include "auv/recon/texture/texture_stage.h"

namespace auv::recon::pipeline {

namespace fs = std::filesystem;

const std::vector<std::string>& stageNames() {
  static const std::vector<std::string> names = {"keyframes", "correct", "features", "match",
                                                 "sfm",       "dense",   "mesh",     "texture"};
  return names;
}

std::string stageOutcomeName(StageOutcome outcome) {
  switch (outcome) {
    case StageOutcome::RAN:
      return "ran";
    case StageOutcome::UP_TO_DATE:
      return "up to date";
  }
  return "?";
}

namespace {
size_t stageIndex(const std::string& name) {
  const auto& names = stageNames();
  return std::find(names.begin(), names.end(), name) - names.begin();
}

template <class F>
void forEachFile(const std::vector<fs::path>& paths, F f) {
  for (const fs::path& path : paths) {
    std::error_code error;
    if (fs::is_regular_file(path, error)) {
      f(fs::last_write_time(path));
      continue;
    }
    if (!fs::is_directory(path, error)) continue;
    for (auto it = fs::recursive_directory_iterator(path, error);
         it != fs::recursive_directory_iterator(); it.increment(error)) {
      if (error) break;
      if (it->path().filename().string().rfind('.', 0) == 0) {  // hidden: staging folders
        if (it->is_directory()) it.disable_recursion_pending();
        continue;
      }
      if (it->is_regular_file()) f(it->last_write_time());
    }
  }
}
}  // namespace

bool newestFileTime(const std::vector<fs::path>& paths, fs::file_time_type& time) {
  bool any = false;
  forEachFile(paths, [&](fs::file_time_type t) {
    time = any ? std::max(time, t) : t;
    any = true;
  });
  return any;
}

bool oldestFileTime(const std::vector<fs::path>& paths, fs::file_time_type& time) {
  bool any = false;
  forEachFile(paths, [&](fs::file_time_type t) {
    time = any ? std::min(time, t) : t;
    any = true;
  });
  return any;
}

bool upToDate(const std::vector<fs::path>& inputs, const std::vector<fs::path>& outputs) {
  fs::file_time_type newest_input, oldest_output;
  if (!newestFileTime(inputs, newest_input)) return false;
  if (!oldestFileTime(outputs, oldest_output)) return false;
  return oldest_output >= newest_input;
}

void PipelineOptions::check() const {
  AUV_RECON_CHECK_OPTION(stageIndex(from) < stageNames().size(), from,
                         "must be one of keyframes, correct, features, match, sfm, dense, mesh, "
                         "texture");
  AUV_RECON_CHECK_OPTION(stageIndex(to) < stageNames().size(), to,
                         "must be one of keyframes, correct, features, match, sfm, dense, mesh, "
                         "texture");
  AUV_RECON_CHECK_OPTION(stageIndex(from) <= stageIndex(to), from, "must not come after `to`");
  AUV_RECON_CHECK_OPTION(config.empty() || fs::is_regular_file(config), config, "no such file");
}

void PipelineOptions::bind(OptionSet& set) {
  set.add("from", &from, "first stage (keyframes correct features match sfm dense mesh texture)");
  set.add("to", &to, "last stage");
  set.add("force", &force, "run stages even when their output is newer than their input");
}

namespace {

/// Sections of a recon.yaml that `run` leaves to other `auv recon` commands reading the same
/// file (its own `run:` is applied by the command); any other name that is not a stage is a
/// typo, refused rather than silently ignored.
const std::vector<std::string> kOtherSections = {"run", "calibrate", "evaluate", "figures"};

/// One stage of the chain: where it reads and writes, and how it runs with its options.
struct StageSpec {
  std::string name;
  std::vector<fs::path> inputs, outputs;
  std::function<std::string()> run;  ///< returns the stage's one-line result
};

/// Options of a stage from the config file's section, through the stage's own bindings; a
/// value out of range names the file and the section too.
template <class Options>
Options configured(const std::string& section, const std::string& config) {
  Options options;
  if (config.empty()) return options;
  OptionSet set(section);
  options.bind(set);
  set.applyConfigFile(config);
  try {
    options.check();
  } catch (const std::invalid_argument& e) {
    throw OptionError(config + ": " + section + ": " + e.what());
  }
  return options;
}

/// Every stage with its options read from the config file, so that a bad value in any
/// section is an error before the first stage runs, not after hours of work.
std::vector<StageSpec> stages(const Survey& survey, const PipelineOptions& options) {
  const std::string& config = options.config;
  const fs::path features = survey.root() / "features";
  std::vector<StageSpec> specs;
  specs.push_back({"keyframes",
                   {survey.recordings()},
                   {survey.keyframes()},
                   [&survey, o = configured<keyframes::KeyframeStageOptions>("keyframes", config)] {
                     const auto r = keyframes::selectSurveyKeyframes(survey, o);
                     int n = 0;
                     for (const auto& c : r.cameras) n += c.keyframes;
                     return std::to_string(n) + " keyframes from " +
                            std::to_string(r.cameras.size()) + " cameras";
                   }});
  specs.push_back({"correct",
                   {survey.keyframes(), survey.calibration()},
                   {survey.corrected()},
                   [&survey, o = configured<color::CorrectStageOptions>("correct", config)] {
                     const auto r = color::correctSurvey(survey, o);
                     int n = 0;
                     for (const auto& c : r.cameras) n += c.images;
                     return std::to_string(n) + " images corrected";
                   }});
  specs.push_back({"features",
                   {survey.corrected()},
                   {features / "index.csv"},
                   [&survey, o = configured<features::ExtractionOptions>("features", config)] {
                     const auto r = features::extractSurveyFeatures(survey, o);
                     return std::to_string(r.images) + " images, " + std::to_string(r.features) +
                            " keypoints";
                   }});
  specs.push_back({"match",
                   {features / "index.csv"},
                   {features / "matches"},
                   [&survey, o = configured<features::MatchStageOptions>("match", config)] {
                     const auto r = features::matchSurvey(survey, o);
                     return std::to_string(r.verified_pairs) + " of " +
                            std::to_string(r.candidate_pairs) + " pairs verified, " +
                            std::to_string(r.verified_matches) + " matches";
                   }});
  specs.push_back({"sfm",
                   {features / "matches", survey.corrected()},
                   {survey.sparse()},
                   [&survey, o = configured<sfm::SfmStageOptions>("sfm", config)] {
                     const auto r = sfm::reconstructSurvey(survey, o);
                     std::ostringstream line;
                     line << r.images_registered << " of " << r.images_total
                          << " images registered, " << r.points << " points, "
                          << r.mean_reprojection_error_px << " px";
                     return line.str();
                   }});
  specs.push_back({"dense",
                   {survey.sparse()},
                   {survey.dense()},
                   [&survey, o = configured<dense::DenseOptions>("dense", config)] {
                     const auto r = dense::runDense(survey, o);
                     return std::to_string(r.depth_maps) + " depth maps, " +
                            std::to_string(r.points) + " points";
                   }});
  specs.push_back({"mesh",
                   {survey.dense()},
                   {survey.mesh()},
                   [&survey, o = configured<mesh::MeshStageOptions>("mesh", config)] {
                     mesh::runMeshStage(survey, o);
                     return std::string("mesh in ") + survey.mesh().string();
                   }});
  specs.push_back({"texture",
                   {survey.mesh(), survey.sparse()},
                   {survey.textured()},
                   [&survey, o = configured<texture::TextureStageOptions>("texture", config)] {
                     texture::runTextureStage(survey, o);
                     return std::string("textured model in ") + survey.textured().string();
                   }});
  return specs;
}

/// Every top-level key of the config file must name a stage (or another command's section):
/// a typo such as `sfn:` would otherwise leave the stage on its defaults without a word.
void checkConfigSections(const std::string& config) {
  if (config.empty()) return;
  YAML::Node root;
  try {
    root = YAML::LoadFile(config);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("--config: " + config + ": " + e.what());
  }
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) throw std::invalid_argument(config + ": expected a map of stage sections");
  for (const auto& entry : root) {
    const std::string section = entry.first.as<std::string>();
    if (stageIndex(section) < stageNames().size()) continue;
    if (std::find(kOtherSections.begin(), kOtherSections.end(), section) != kOtherSections.end()) {
      continue;
    }
    throw std::invalid_argument(config + ": section '" + section +
                                "': unknown (stages: keyframes, correct, features, match, sfm, "
                                "dense, mesh, texture; also run, calibrate, evaluate, figures)");
  }
}

}  // namespace

PipelineSummary runPipeline(const Survey& survey, const PipelineOptions& options,
                            std::ostream& log) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  checkConfigSections(options.config);
  const std::vector<StageSpec> specs = stages(survey, options);
  PipelineSummary summary;
  for (size_t i = stageIndex(options.from); i <= stageIndex(options.to); ++i) {
    const StageSpec& spec = specs[i];
    StageReport report;
    report.stage = spec.name;
    const auto stage_start = std::chrono::steady_clock::now();
    if (!options.force && upToDate(spec.inputs, spec.outputs)) {
      report.outcome = StageOutcome::UP_TO_DATE;
      report.note = "output newer than its input: skipped (--force to run it)";
    } else {
      log << "run: " << spec.name << " ..." << std::endl;
      report.note = spec.run();
    }
    report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start).count();
    log << "run: " << spec.name << ": " << stageOutcomeName(report.outcome) << ": " << report.note;
    if (report.outcome == StageOutcome::RAN) log << " (" << report.seconds << " s)";
    log << std::endl;
    summary.stages.push_back(report);
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace auv::recon::pipeline
