#pragma once
// Strict reading of one YAML mapping of a file (a scenario, a mission, options), so that a bad
// value names the file and the field ("canyon.yaml: sonar.range: expected a number > 0, got
// 'far'") and a misspelt key is an error with a suggestion instead of a silently ignored
// setting. Scalars follow the one rule of yaml_scalars.h (the YAML 1.2 core schema: "yes" is not
// a boolean, "1_000" not a number, a quoted "5" is a string).

#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "auv/config/errors.h"

namespace auv::config {

class YamlSection {
 public:
  /// `node` must be a map or null (an absent section); `path` is its dotted name ("" = root).
  YamlSection(YAML::Node node, std::string path, std::string file);

  bool has(const std::string& key) const;
  /// The sub-map `key`; an absent key gives an empty section (defaults apply).
  YamlSection child(const std::string& key) const;
  /// Elements of the sequence `key` that are maps (e.g. cameras, queries); absent = empty.
  std::vector<YamlSection> childList(const std::string& key) const;

  /// Reads `key` into `value` when present (keeps the default otherwise), converting strictly
  /// and checking [min, max]. Throws ConfigError naming file and field.
  void read(const std::string& key, double& value, std::optional<double> min = {},
            std::optional<double> max = {}) const;
  void read(const std::string& key, float& value, std::optional<double> min = {},
            std::optional<double> max = {}) const;
  void read(const std::string& key, int& value, std::optional<int> min = {},
            std::optional<int> max = {}) const;
  void read(const std::string& key, bool& value) const;
  void read(const std::string& key, std::string& value) const;
  /// A 3-element sequence of numbers; each element checked against [min, max].
  void read(const std::string& key, Eigen::Vector3d& value, std::optional<double> min = {},
            std::optional<double> max = {}) const;
  /// A sequence of numbers of any length.
  void read(const std::string& key, std::vector<double>& value) const;
  /// An angle written in degrees under `key` (e.g. `step_deg`) into a field kept in radians.
  void readDegrees(const std::string& key, double& radians, std::optional<double> min_deg = {},
                   std::optional<double> max_deg = {}) const;

  /// Throws ConfigError for any key not in `known` (suggesting the closest known key, listing
  /// them all), for a key given twice and for a key that is not a plain name.
  void rejectUnknownKeys(const std::vector<std::string>& known) const;
  /// Throws the "unknown setting" error of rejectUnknownKeys for `key` (for readers that match
  /// keys themselves, e.g. accepting another spelling).
  [[noreturn]] void unknownKey(const std::string& key, const std::vector<std::string>& known) const;

  /// "file: path.key" for messages.
  std::string where(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& node() const { return node_; }

 private:
  YAML::Node scalar(const std::string& key, const char* expected) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
};

/// Throws ConfigError "<field>: expected <what>, got <value>" unless `ok` (for options'
/// check(): `field` is the dotted name, e.g. "sonar.max_range").
void requireOption(bool ok, const std::string& field, const std::string& what, double value);

/// Loads a YAML file whose root is a map; errors name the file ("<file>: cannot open the file",
/// "<file>:<line>:<column>: malformed YAML: ..."). An empty file is an empty root section when
/// `allow_empty`, else an error.
YamlSection loadYamlFile(const std::string& file, bool allow_empty = false);
/// The same for YAML text held in memory; `source` names it in messages.
YamlSection loadYamlText(const std::string& text, const std::string& source,
                         bool allow_empty = false);

}  // namespace auv::config
