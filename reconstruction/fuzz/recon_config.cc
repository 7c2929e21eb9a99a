// Fuzz harness: recon.yaml, the `--config` file of `auv recon run` and of every stage's command
// (OptionSet::applyConfigFile: the shared strict loader, then each section through the stage's
// own bindings, then the stage's Options::check()), for every stage of stages.cc and the `run:`
// section. The text is read in memory with the loader applyConfigFile uses on the file. A clear
// error is a std::invalid_argument (OptionError) or a config::ConfigError naming the file, the
// section and the key; anything else (a crash, a sanitizer report, another exception) is a bug.
#include <cstdint>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "auv/config/yaml_section.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/pipeline/pipeline.h"
#include "auv/recon/pipeline/stages.h"

using auv::config::ConfigError;
using auv::config::YamlSection;
using auv::recon::OptionSet;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  YamlSection root(YAML::Node(), "", "");
  try {
    root = auv::config::loadYamlText(input, "fuzz_recon.yaml", /*allow_empty=*/true);
  } catch (const ConfigError&) {
    return 0;
  }
  for (const auv::recon::Stage* stage : auv::recon::pipeline::stages()) {
    const std::unique_ptr<auv::recon::StageOptions> options = stage->defaultOptions();
    OptionSet set(stage->name());
    options->bind(set);
    try {
      set.applyYaml(root.child(stage->name()));
      options->check();
    } catch (const std::invalid_argument&) {
    } catch (const ConfigError&) {
    }
  }
  auv::recon::pipeline::PipelineOptions run;
  OptionSet set("run");
  run.bind(set);
  try {
    set.applyYaml(root.child("run"));
    run.check();
  } catch (const std::invalid_argument&) {
  } catch (const ConfigError&) {
  }
  return 0;
}

namespace {

/// `section:` with every option of `set` at its default, from the set's own help (the keys and
/// defaults `auv recon <stage> --help` lists).
std::string defaultsSection(const OptionSet& set) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << set.section() << YAML::Value << YAML::BeginMap;
  std::istringstream help(set.help());
  std::string flag;
  for (std::string line; std::getline(help, line);) {
    if (line.rfind("  --", 0) == 0) {
      flag = line.substr(4, line.find(' ', 4) - 4);
      continue;
    }
    const size_t at = line.rfind("(default ");
    if (flag.empty() || flag == "config" || at == std::string::npos || line.back() != ')') continue;
    const std::string value = line.substr(at + 9, line.size() - at - 10);
    for (char& c : flag) c = c == '-' ? '_' : c;
    if (value != "none") out << YAML::Key << flag << YAML::Value << value;
    flag.clear();
  }
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace

/// A recon.yaml with every stage's section at its defaults, each section alone, and the
/// examples of pipeline/README.md.
std::vector<std::string> auvFuzzSeeds() {
  std::vector<std::string> seeds;
  std::string all;
  for (const auv::recon::Stage* stage : auv::recon::pipeline::stages()) {
    const std::unique_ptr<auv::recon::StageOptions> options = stage->defaultOptions();
    OptionSet set(stage->name());
    options->bind(set);
    seeds.push_back(defaultsSection(set));
    all += seeds.back();
  }
  auv::recon::pipeline::PipelineOptions run;
  OptionSet set("run");
  run.bind(set);
  seeds.push_back(defaultsSection(set));
  all += seeds.back();
  seeds.push_back(all);
  seeds.push_back(
      "sfm: {max_reprojection_error: 2, loss: huber}\ndense: {max_image_size: 512}\n"
      "run: {from: features, to: sfm, force: true}\n");
  seeds.push_back("features:\n  threads: 2\nmatch:\n  threads: 2\nsfm:\n  threads: 2\n");
  return seeds;
}
