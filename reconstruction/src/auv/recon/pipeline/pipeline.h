#pragma once
// `auv recon run <survey>`: the chained stages of stages.h in the paper's order (section 3:
// keyframes -> correct -> features -> match -> sfm -> dense -> mesh -> texture) over one survey
// folder (docs/design.md §6), each through its Stage (common/stage.h). A stage whose outputs
// are newer than all of its inputs is skipped (unless `force`), so a run continues where an
// earlier one stopped and re-runs only what changed.

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"

namespace auv::recon {
class OptionSet;
}

namespace auv::recon::pipeline {

/// The names of the stages `run` chains, in order (stages.h).
const std::vector<std::string>& stageNames();

struct PipelineOptions {
  std::string from = "keyframes";  ///< first stage run
  std::string to = "texture";      ///< last stage run
  bool force = false;              ///< run stages even when their output is up to date
  /// Go on after a stage's partial result (e.g. SfM registering fewer images than its
  /// min_registered_ratio): sets that stage's own accept_partial.
  bool accept_partial = false;
  /// recon.yaml: one section per stage (`sfm:`, `dense:`, ...), the same keys as the stages'
  /// flags (each stage's Options::bind). Empty: defaults.
  std::string config;
  /// Sharded runs (cluster/README.md), for one shardable stage (from == to): "i/N" runs shard
  /// i (0-based) of N into its own folder; merge_shards = N writes the stage's output from
  /// them. The Slurm executor's jobs use them; by hand they serve a re-run of one shard.
  std::string shard;
  int merge_shards = 0;

  /// Throws OptionError naming the field: unknown stage, `from` after `to`, missing config.
  void check() const;
  void bind(OptionSet& set);
};

enum class StageOutcome { RAN, UP_TO_DATE };
std::string stageOutcomeName(StageOutcome outcome);

/// One stage of a run.
struct PipelineStep {
  std::string stage;
  StageOutcome outcome = StageOutcome::RAN;
  double seconds = 0;
  std::string note;  ///< the stage's one-line result (StageReport::summary), or why it was skipped
};

struct PipelineResult {
  std::vector<PipelineStep> stages;
  double seconds = 0;
};

/// "I/N" -> Shard; throws OptionError.
Shard parseShard(const std::string& text);

/// What runPipeline checks before its first stage: the options, the config file's sections and
/// every stage's values in it. Throws std::invalid_argument naming the file, section and key.
void checkPipeline(const PipelineOptions& options);

/// Runs the stages from `options.from` to `options.to`; `log` gets one line per stage. The
/// config file is read before any stage runs: a section that names no stage (nor `run`,
/// `calibrate`, `evaluate`, `figures`), an unknown key or a bad value throws
/// std::invalid_argument naming the file, section and key. A stage's failure (StageError
/// naming it) stops the run and propagates; the outputs of the stages before it stay (each
/// stage writes through a staging folder).
PipelineResult runPipeline(const Survey& survey, const PipelineOptions& options, std::ostream& log);

/// Newest modification time of the files under `paths` (files or folders, hidden entries
/// skipped); false when there is no file at all.
bool newestFileTime(const std::vector<std::filesystem::path>& paths,
                    std::filesystem::file_time_type& time);
/// Oldest modification time of the files under `paths`; false when there is no file.
bool oldestFileTime(const std::vector<std::filesystem::path>& paths,
                    std::filesystem::file_time_type& time);
/// A stage's output is up to date when it has files, all at least as new as every input
/// file (and there is input).
bool upToDate(const std::vector<std::filesystem::path>& inputs,
              const std::vector<std::filesystem::path>& outputs);

}  // namespace auv::recon::pipeline
