#pragma once
// Binds a stage's Options fields to command-line flags and to a section of a YAML file, with
// one declaration per field:
//
//   OptionSet set("keyframes");
//   set.add("min_motion_px", &options.min_motion_px, "px: mean feature motion for a new keyframe");
//   set.parse(args);   // --min-motion-px 40, --config recon.yaml (section `keyframes:`)
//
// Flags are the names with '-' for '_' (both spellings accepted). Values are checked for type
// here, by the one scalar rule of every reader (YAML 1.2 core schema, for flags and the file
// alike: auv/config/yaml_scalars.h), and for range by the stage's Options::check(); errors name
// the flag or the file and key.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "auv/config/yaml_section.h"

namespace auv::recon {

class OptionSet {
 public:
  /// `section`: the YAML key holding this set's values (the command's name).
  explicit OptionSet(std::string section);

  /// Supported T: double, float, int, unsigned, size_t, int64_t, bool, std::string,
  /// std::vector<std::string> (repeatable flag; a YAML list). The variable's current value is
  /// the default shown in help.
  template <class T>
  void add(const std::string& name, T* value, const std::string& help);

  /// Positional arguments, in order; `required` ones missing are a usage error.
  void positional(const std::string& name, std::string* value, const std::string& help,
                  bool required = true);

  /// Applies `--config <file>` first (wherever it stands), then the flags in order. Returns
  /// false when `--help` was asked for (the help is printed to stdout). Throws
  /// std::invalid_argument naming the flag, file or key.
  bool parse(const std::vector<std::string>& args);

  /// Applies the `section_` key of a YAML file (absent section: nothing), read with the shared
  /// strict reader (auv/config/yaml_section.h): values by the one YAML 1.2 scalar rule, unknown
  /// keys named with the file and a did-you-mean. Throws std::invalid_argument (exit code 2).
  void applyConfigFile(const std::filesystem::path& file);
  /// Applies one section of options (a map; absent or empty: nothing). Throws
  /// std::invalid_argument or config::ConfigError (both exit code 2) naming file and key.
  void applyYaml(const config::YamlSection& section);

  /// True when an option `name` was added.
  bool has(const std::string& name) const;

  /// Options and positionals with help and defaults.
  std::string help() const;
  const std::string& section() const { return section_; }

 private:
  struct Entry {
    std::string name, help, default_text, type;
    bool is_flag = false, repeatable = false;
    std::function<void(const std::string&)> set;                          // from text
    std::function<void(const YAML::Node&, const std::string&)> set_yaml;  // from YAML, where
  };
  struct Positional {
    std::string name, help;
    std::string* value;
    bool required;
  };
  Entry* find(const std::string& name);

  std::string section_;
  std::vector<Entry> entries_;
  std::vector<Positional> positionals_;
};

}  // namespace auv::recon
