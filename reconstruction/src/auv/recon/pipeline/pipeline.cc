#include "auv/recon/pipeline/pipeline.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <ostream>
#include <sstream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/features/sift_extractor.h"
#include "auv/recon/sfm/sfm_stage.h"

// The stages of other folders are wired when their library is in the tree.
#if __has_include("auv/recon/keyframes/stage.h")
#include "auv/recon/keyframes/stage.h"
#define AUV_RECON_HAS_KEYFRAMES 1
#endif
#if __has_include("auv/recon/color/correct_stage.h")
#include "auv/recon/color/correct_stage.h"
#define AUV_RECON_HAS_CORRECT 1
#endif
#if __has_include("auv/recon/dense/dense_stage.h")
#include "auv/recon/dense/dense_stage.h"
#define AUV_RECON_HAS_DENSE 1
#endif
#if __has_include("auv/recon/mesh/mesh_stage.h")
#include "auv/recon/mesh/mesh_stage.h"
#define AUV_RECON_HAS_MESH 1
#endif
#if __has_include("auv/recon/texture/texture_stage.h")
#include "auv/recon/texture/texture_stage.h"
#define AUV_RECON_HAS_TEXTURE 1
#endif

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
    case StageOutcome::NOT_BUILT:
      return "not built yet";
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

/// One stage of the chain: where it reads and writes, and how it runs (empty: not built).
struct StageSpec {
  std::string name;
  std::vector<fs::path> inputs, outputs;
  std::function<std::string()> run;  ///< returns the stage's one-line result
  bool binds_options = false;        ///< its options take the config file's section
};

/// Options of a stage from the config file's section, through the stage's own bindings.
template <class Options>
Options configured(const std::string& section, const std::string& config) {
  Options options;
  if (!config.empty()) {
    OptionSet set(section);
    options.bind(set);
    set.applyConfigFile(config);
  }
  options.check();
  return options;
}

std::vector<StageSpec> stages(const Survey& survey, const PipelineOptions& options) {
  const std::string& config = options.config;
  const fs::path features = survey.root() / "features";
  std::vector<StageSpec> specs;
  StageSpec keyframes{"keyframes", {survey.recordings()}, {survey.keyframes()}, nullptr, false};
#ifdef AUV_RECON_HAS_KEYFRAMES
  keyframes.run = [&survey] {
    keyframes::KeyframeStageOptions o;
    o.check();
    const auto r = keyframes::selectSurveyKeyframes(survey, o);
    int n = 0;
    for (const auto& c : r.cameras) n += c.keyframes;
    return std::to_string(n) + " keyframes from " + std::to_string(r.cameras.size()) + " cameras";
  };
#endif
  specs.push_back(keyframes);
  StageSpec correct{
      "correct", {survey.keyframes(), survey.calibration()}, {survey.corrected()}, nullptr, false};
#ifdef AUV_RECON_HAS_CORRECT
  correct.run = [&survey] {
    color::CorrectStageOptions o;
    o.check();
    const auto r = color::correctSurvey(survey, o);
    int n = 0;
    for (const auto& c : r.cameras) n += c.images;
    return std::to_string(n) + " images corrected";
  };
#endif
  specs.push_back(correct);
  specs.push_back({"features",
                   {survey.corrected()},
                   {features / "index.csv"},
                   [&survey, config] {
                     const auto o = configured<features::ExtractionOptions>("features", config);
                     const auto r = features::extractSurveyFeatures(survey, o);
                     return std::to_string(r.images) + " images, " + std::to_string(r.features) +
                            " keypoints";
                   },
                   true});
  specs.push_back({"match",
                   {features / "index.csv"},
                   {features / "matches"},
                   [&survey, config] {
                     const auto o = configured<features::MatchStageOptions>("match", config);
                     const auto r = features::matchSurvey(survey, o);
                     return std::to_string(r.verified_pairs) + " of " +
                            std::to_string(r.candidate_pairs) + " pairs verified, " +
                            std::to_string(r.verified_matches) + " matches";
                   },
                   true});
  specs.push_back({"sfm",
                   {features / "matches", survey.corrected()},
                   {survey.sparse()},
                   [&survey, config] {
                     const auto o = configured<sfm::SfmStageOptions>("sfm", config);
                     const auto r = sfm::reconstructSurvey(survey, o);
                     std::ostringstream line;
                     line << r.images_registered << " of " << r.images_total
                          << " images registered, " << r.points << " points, "
                          << r.mean_reprojection_error_px << " px";
                     return line.str();
                   },
                   true});
  StageSpec dense{"dense", {survey.sparse()}, {survey.dense()}, nullptr, false};
#ifdef AUV_RECON_HAS_DENSE
  dense.run = [&survey] {
    dense::DenseOptions o;
    o.check();
    dense::runDense(survey, o);
    return std::string("dense cloud in ") + survey.dense().string();
  };
#endif
  specs.push_back(dense);
  StageSpec mesh{"mesh", {survey.dense()}, {survey.mesh()}, nullptr, false};
#ifdef AUV_RECON_HAS_MESH
  mesh.run = [&survey] {
    mesh::MeshStageOptions o;
    o.check();
    mesh::runMeshStage(survey, o);
    return std::string("mesh in ") + survey.mesh().string();
  };
#endif
  specs.push_back(mesh);
  StageSpec texture{
      "texture", {survey.mesh(), survey.sparse()}, {survey.textured()}, nullptr, false};
#ifdef AUV_RECON_HAS_TEXTURE
  texture.run = [&survey] {
    texture::TextureStageOptions o;
    o.check();
    texture::runTextureStage(survey, o);
    return std::string("textured model in ") + survey.textured().string();
  };
#endif
  specs.push_back(texture);
  return specs;
}

/// Sections of the config file for stages whose options `run` cannot bind yet: an error
/// rather than settings silently ignored.
void checkConfigSections(const std::string& config, const std::vector<StageSpec>& specs) {
  if (config.empty()) return;
  YAML::Node root;
  try {
    root = YAML::LoadFile(config);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(config + ": not YAML: " + e.what());
  }
  if (!root.IsMap()) return;
  for (const auto& entry : root) {
    const std::string section = entry.first.as<std::string>();
    auto spec = std::find_if(specs.begin(), specs.end(),
                             [&](const StageSpec& s) { return s.name == section; });
    if (spec != specs.end() && !spec->binds_options) {
      throw std::invalid_argument(config + ": section '" + section +
                                  "': `auv recon run` cannot pass options to this stage yet; "
                                  "run `auv recon " +
                                  section + " --config " + config +
                                  "` on its own, then `auv recon run --from` the next stage");
    }
  }
}

}  // namespace

PipelineSummary runPipeline(const Survey& survey, const PipelineOptions& options,
                            std::ostream& log) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const std::vector<StageSpec> specs = stages(survey, options);
  checkConfigSections(options.config, specs);
  PipelineSummary summary;
  for (size_t i = stageIndex(options.from); i <= stageIndex(options.to); ++i) {
    const StageSpec& spec = specs[i];
    StageReport report;
    report.stage = spec.name;
    const auto stage_start = std::chrono::steady_clock::now();
    if (!spec.run) {
      report.outcome = StageOutcome::NOT_BUILT;
      report.note = "its library is not built yet: left out";
    } else if (!options.force && upToDate(spec.inputs, spec.outputs)) {
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
