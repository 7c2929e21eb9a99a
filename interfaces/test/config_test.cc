// auv_config: the one exit-code rule of every `auv` command and the strict YAML reader that
// names file and field.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "auv/config/errors.h"
#include "auv/config/yaml_section.h"
#include "auv/interfaces/parameters.h"

namespace auv::config {
namespace {

TEST(ExitCodeRule, InputErrorsAreTwoAndFailuresOne) {
  EXPECT_EQ(exitCodeFor(ConfigError("x")), 2);
  EXPECT_EQ(exitCodeFor(interfaces::ParameterError("rate: expected > 0")), 2);
  EXPECT_EQ(exitCodeFor(std::invalid_argument("an options check()")), 2);
  EXPECT_EQ(exitCodeFor(RuntimeFailure("the peer vanished")), 1);
  EXPECT_EQ(exitCodeFor(std::runtime_error("anything else")), 1);
  EXPECT_EQ(exitCodeFor(std::bad_alloc()), 1);
}

TEST(YamlSectionTest, ReadsStrictlyAndNamesFileAndField) {
  const YamlSection root(YAML::Load("sonar: {range: far, beams: 0x10, on: yes, step: 2}"), "",
                         "site.yaml");
  const YamlSection sonar = root.child("sonar");
  double range = 0;
  try {
    sonar.read("range", range, 0.0);
    FAIL() << "accepted 'far'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("site.yaml: sonar.range"), std::string::npos) << e.what();
  }
  int beams = 0;
  EXPECT_THROW(sonar.read("beams", beams), ConfigError);  // YAML 1.2: no hex
  bool on = false;
  EXPECT_THROW(sonar.read("on", on), ConfigError);  // YAML 1.2: yes is not a boolean
  double step = 0;
  EXPECT_THROW(sonar.read("step", step, 0.0, 1.0), ConfigError);  // out of range
  try {
    sonar.rejectUnknownKeys({"range", "beams", "on", "stop"});
    FAIL() << "accepted 'step'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'stop'"), std::string::npos) << e.what();
  }
  double absent = 7;
  sonar.read("absent", absent);
  EXPECT_EQ(absent, 7);  // defaults stay
}

TEST(YamlSectionTest, FileErrorsNameTheFileAndLine) {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / "auv_config_test_bad.yaml";
  {
    std::ofstream out(file);
    out << "a: 1\nb: [1, 2\n";
  }
  try {
    loadYamlFile(file.string());
    FAIL() << "read a broken file";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string() + ": line"), std::string::npos) << what;
  }
  std::filesystem::remove(file);
  EXPECT_THROW(loadYamlFile(file.string()), ConfigError);  // missing: named, exit code 2
}

}  // namespace
}  // namespace auv::config
