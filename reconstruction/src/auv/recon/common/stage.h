#pragma once
// A reconstruction stage: one step of docs/paper.md §3 over one survey folder
// (docs/design.md §6). Every stage is a Stage, listed once in pipeline/stages.cc; from that list
// come `auv recon <stage>` (its flags, help and output), `auv recon run` (the chained stages in
// order, skipping those whose outputs are newer than their inputs) and the sections a recon.yaml
// may hold. Adding a stage: pipeline/README.md.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "auv/recon/common/survey.h"

namespace auv::recon {

class OptionSet;

/// A stage's options, whatever their type: bound to flags and to the stage's recon.yaml section
/// (OptionSet), checked for range before the stage runs.
class StageOptions {
 public:
  virtual ~StageOptions() = default;
  virtual void bind(OptionSet& set) = 0;
  /// Throws OptionError (std::invalid_argument) naming the field and the value.
  virtual void check() const = 0;
};

/// A stage's Options struct (fields + bind() + check(), as every stage declares them) as
/// StageOptions.
template <class Options>
class StageOptionsOf final : public StageOptions {
 public:
  void bind(OptionSet& set) override { value.bind(set); }
  void check() const override { value.check(); }
  Options value;
};

/// What a stage did, the same for every stage: what its command prints and what `run` logs.
struct StageReport {
  /// `run: <stage>: ran: <summary>`: the one-line result.
  std::string summary;
  /// The lines `auv recon <stage>` prints on stdout (each starting with `<stage>: `).
  std::vector<std::string> lines;
  /// Printed on stderr as `auv recon <stage>: warning: <warning>`.
  std::vector<std::string> warnings;
};

/// One piece of a sharded run: `index` (0-based) of `count`.
struct Shard {
  int index = 0;
  int count = 1;
  /// Throws std::invalid_argument ("shard I/N: ...") unless 0 <= index < count.
  void check() const;
};

/// `<survey>/.shards/<stage>/<index>-of-<count>/`: where a shard writes (hidden, so that the
/// up-to-date rule of the stage's own outputs never sees it).
std::filesystem::path shardFolder(const Survey& survey, const std::string& stage, Shard shard);

/// What a shard's run reports: summary "shard I of N: <done>" and the line "<stage>: <summary>".
StageReport shardReport(const std::string& stage, Shard shard, const std::string& done);
/// A merge's report: the stage's own `whole` with " (N shards merged)" on its summary.
StageReport mergedReport(StageReport whole, int count);

class Stage {
 public:
  virtual ~Stage() = default;

  /// As on the command line (`auv recon <name>`), in recon.yaml and in report.json.
  virtual std::string name() const = 0;
  /// The arguments and the one-line description of `auv recon --help`, e.g.
  /// "<survey>   select sharp keyframes from the recordings".
  virtual std::string usage() const = 0;
  /// Help of the `<survey>` argument: what the stage reads and writes.
  virtual std::string surveyHelp() const = 0;
  /// Whether `auv recon run` chains the stage (calibrate, evaluate and figures need more than
  /// the survey folder: a chessboard recording, the simulated run). Chained stages must declare
  /// their inputs and outputs.
  virtual bool chained() const { return true; }

  /// Survey-folder files or folders the stage reads and writes. `run` skips a chained stage
  /// whose outputs are all at least as new as its newest input (pipeline/pipeline.h). A stage
  /// bringing data from outside the survey (an import of footage into recordings/) has no
  /// inputs here and always runs; one comparing two surveys reads the other through its
  /// options and declares this survey's files.
  virtual std::vector<std::filesystem::path> inputs(const Survey& survey) const = 0;
  virtual std::vector<std::filesystem::path> outputs(const Survey& survey) const = 0;

  /// Sharded runs (cluster/README.md): a stage whose work splits into independent pieces runs
  /// piece `shard` into shardFolder(survey, name(), shard), each maybe on another machine, and
  /// mergeShards then writes the stage's outputs as a whole run would have (the same files).
  /// False: the stage runs whole, and the two below throw std::logic_error.
  virtual bool shardable() const { return false; }
  virtual StageReport runShard(const Survey& survey, const StageOptions& options,
                               Shard shard) const;
  virtual StageReport mergeShards(const Survey& survey, const StageOptions& options,
                                  int count) const;

  /// The stage's options at their defaults.
  virtual std::unique_ptr<StageOptions> defaultOptions() const = 0;
  /// Runs the stage with options from defaultOptions() (bound and checked). Throws StageError
  /// naming the stage and the cause; the stage's earlier output then stays intact.
  virtual StageReport run(const Survey& survey, const StageOptions& options) const = 0;
};

/// A Stage whose options are an `Options` struct: implement runWith().
template <class Options>
class StageWith : public Stage {
 public:
  std::unique_ptr<StageOptions> defaultOptions() const override {
    return std::make_unique<StageOptionsOf<Options>>();
  }
  StageReport run(const Survey& survey, const StageOptions& options) const override {
    return runWith(survey, dynamic_cast<const StageOptionsOf<Options>&>(options).value);
  }
  virtual StageReport runWith(const Survey& survey, const Options& options) const = 0;

  StageReport runShard(const Survey& survey, const StageOptions& options,
                       Shard shard) const override {
    return runShardWith(survey, dynamic_cast<const StageOptionsOf<Options>&>(options).value, shard);
  }
  StageReport mergeShards(const Survey& survey, const StageOptions& options,
                          int count) const override {
    return mergeShardsWith(survey, dynamic_cast<const StageOptionsOf<Options>&>(options).value,
                           count);
  }
  /// For shardable() stages.
  virtual StageReport runShardWith(const Survey& survey, const Options& /*options*/,
                                   Shard shard) const {
    return Stage::runShard(survey, StageOptionsOf<Options>(), shard);  // throws
  }
  virtual StageReport mergeShardsWith(const Survey& survey, const Options& /*options*/,
                                      int count) const {
    return Stage::mergeShards(survey, StageOptionsOf<Options>(), count);  // throws
  }
};

}  // namespace auv::recon
