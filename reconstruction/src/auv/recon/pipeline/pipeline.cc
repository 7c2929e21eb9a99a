#include "auv/recon/pipeline/pipeline.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <ostream>
#include <sstream>

#include "auv/config/spelling.h"
#include "auv/config/yaml_section.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/pipeline/stages.h"

namespace auv::recon::pipeline {

namespace fs = std::filesystem;

const std::vector<std::string>& stageNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> chained;
    for (const Stage* stage : chainedStages()) chained.push_back(stage->name());
    return chained;
  }();
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

std::string joined(const std::vector<std::string>& names, const std::string& separator) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : separator) + name;
  return text;
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
  const std::string one_of = "must be one of " + joined(stageNames(), ", ");
  AUV_RECON_CHECK_OPTION(stageIndex(from) < stageNames().size(), from, one_of.c_str());
  AUV_RECON_CHECK_OPTION(stageIndex(to) < stageNames().size(), to, one_of.c_str());
  AUV_RECON_CHECK_OPTION(stageIndex(from) <= stageIndex(to), from, "must not come after `to`");
  AUV_RECON_CHECK_OPTION(config.empty() || fs::is_regular_file(config), config, "no such file");
  AUV_RECON_CHECK_OPTION(merge_shards >= 0, merge_shards, "must be >= 0 (0: no merge)");
  if (shard.empty() && merge_shards == 0) return;
  AUV_RECON_CHECK_OPTION(shard.empty() || merge_shards == 0, shard,
                         "a run is a shard or a merge, not both");
  AUV_RECON_CHECK_OPTION(from == to, from, "a shard or a merge runs one stage: from == to");
  AUV_RECON_CHECK_OPTION(
      stageIndex(from) < stageNames().size() && chainedStages()[stageIndex(from)]->shardable(),
      from, "this stage is not sharded");
  if (!shard.empty()) parseShard(shard);
}

Shard parseShard(const std::string& text) {
  Shard shard;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> shard.index >> slash >> shard.count) || slash != '/' || !in.eof() ||
      shard.count < 1 || shard.index < 0 || shard.index >= shard.count) {
    throw OptionError("shard = " + text + ": expected I/N with 0 <= I < N");
  }
  return shard;
}

void PipelineOptions::bind(OptionSet& set) {
  set.add("from", &from, "first stage (" + joined(stageNames(), " ") + ")");
  set.add("to", &to, "last stage");
  set.add("force", &force, "run stages even when their output is newer than their input");
  set.add("accept_partial", &accept_partial,
          "go on after a partial result (sfm: fewer images registered than asked for)");
  set.add("shard", &shard,
          "I/N: only shard I (0-based) of N of one shardable stage (--from = --to), into "
          ".shards/ (the Slurm executor's jobs; cluster/README.md)");
  set.add("merge_shards", &merge_shards,
          "N: write the stage's output from its N shards (0: no merge)");
}

namespace {

/// Sections of a recon.yaml that `run` leaves to other `auv recon` commands reading the same
/// file: its own `run:` (applied by the command) and the stages it does not chain; any other
/// name that is not a stage is a typo, refused rather than silently ignored.
std::vector<std::string> otherSections() {
  std::vector<std::string> names = {"run"};
  for (const Stage* stage : stages()) {
    if (!stage->chained()) names.push_back(stage->name());
  }
  return names;
}

/// A chained stage with its options read from the config file's section, through the stage's
/// own bindings; a value out of range names the file and the section too.
struct ConfiguredStage {
  const Stage* stage;
  std::unique_ptr<StageOptions> options;
};

ConfiguredStage configured(const Stage& stage, const std::string& config, bool accept_partial) {
  ConfiguredStage configured{&stage, stage.defaultOptions()};
  OptionSet set(stage.name());
  configured.options->bind(set);
  if (accept_partial && set.has("accept_partial")) set.parse({"--accept-partial"});
  if (config.empty()) return configured;
  set.applyConfigFile(config);
  try {
    configured.options->check();
  } catch (const std::invalid_argument& e) {
    throw OptionError(config + ": " + stage.name() + ": " + e.what());
  }
  return configured;
}

/// Every top-level key of the config file must name a stage (or another command's section):
/// a typo such as `sfn:` would otherwise leave the stage on its defaults without a word.
void checkConfigSections(const std::string& config) {
  if (config.empty()) return;
  const config::YamlSection root = [&] {
    try {
      return config::loadYamlFile(config, true);  // the shared strict loader; empty: no sections
    } catch (const config::ConfigError& e) {
      throw std::invalid_argument(std::string("--config: ") + e.what());
    }
  }();
  if (!root.node().IsMap()) return;
  const std::vector<std::string> others = otherSections();
  std::vector<std::string> known = stageNames();
  known.insert(known.end(), others.begin(), others.end());
  for (const auto& entry : root.node()) {
    const std::string section = entry.first.IsScalar() ? entry.first.Scalar() : "";
    if (std::find(known.begin(), known.end(), section) != known.end()) continue;
    const std::string hint = config::closestMatch(section, known);
    throw std::invalid_argument(config + ": section '" + section + "': unknown" +
                                (hint.empty() ? "" : " (did you mean '" + hint + "'?)") +
                                "; stages: " + joined(stageNames(), ", ") + "; also " +
                                joined(others, ", "));
  }
}

/// Every chained stage with its options. Every stage's options are read first, so that a bad
/// value in any section is an error before the first stage runs, not after hours of work.
std::vector<ConfiguredStage> configuredChain(const PipelineOptions& options) {
  options.check();
  checkConfigSections(options.config);
  std::vector<ConfiguredStage> chain;
  for (const Stage* stage : chainedStages()) {
    chain.push_back(configured(*stage, options.config, options.accept_partial));
  }
  return chain;
}

}  // namespace

void checkPipeline(const PipelineOptions& options) { configuredChain(options); }

PipelineResult runPipeline(const Survey& survey, const PipelineOptions& options,
                           std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<ConfiguredStage> chain = configuredChain(options);
  PipelineResult result;
  for (size_t i = stageIndex(options.from); i <= stageIndex(options.to); ++i) {
    const Stage& stage = *chain[i].stage;
    PipelineStep step;
    step.stage = stage.name();
    const auto stage_start = std::chrono::steady_clock::now();
    const bool whole_up_to_date =
        !options.force && upToDate(stage.inputs(survey), stage.outputs(survey));
    const Shard shard = options.shard.empty() ? Shard{} : parseShard(options.shard);
    if (whole_up_to_date ||
        (!options.shard.empty() && !options.force &&
         upToDate(stage.inputs(survey), {shardFolder(survey, step.stage, shard)}))) {
      step.outcome = StageOutcome::UP_TO_DATE;
      step.note = "output newer than its input: skipped (--force to run it)";
    } else {
      log << "run: " << step.stage << " ..." << std::endl;
      const StageReport report =
          !options.shard.empty() ? stage.runShard(survey, *chain[i].options, shard)
          : options.merge_shards
              ? stage.mergeShards(survey, *chain[i].options, options.merge_shards)
              : stage.run(survey, *chain[i].options);
      step.note = report.summary;
      for (const std::string& warning : report.warnings) {
        log << "run: " << step.stage << ": warning: " << warning << std::endl;
      }
    }
    step.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start).count();
    log << "run: " << step.stage << ": " << stageOutcomeName(step.outcome) << ": " << step.note;
    if (step.outcome == StageOutcome::RAN) log << " (" << step.seconds << " s)";
    log << std::endl;
    result.stages.push_back(step);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace auv::recon::pipeline
