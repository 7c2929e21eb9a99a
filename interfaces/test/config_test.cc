// auv_config: the one exit-code rule of every `auv` command and the strict YAML reader that
// names file and field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "auv/config/errors.h"
#include "auv/config/option_table.h"
#include "auv/config/yaml_section.h"
#include "auv/interfaces/option_parameters.h"
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

namespace auv::config {
namespace {

struct SonarOptions {
  double prob_hit = 0.7;
  double range = 20;
  static const OptionTable<SonarOptions>& table() {
    static const OptionTable<SonarOptions> kTable = {
        {"prob_hit", &SonarOptions::prob_hit, "hit probability", "", Range::open(0.5, 1.0)},
        {"range", &SonarOptions::range, "maximum range", "m", Range::aboveUpTo(0, 100)}};
    return kTable;
  }
};

TEST(OptionTableTest, RangesHaveOpenAndClosedEnds) {
  EXPECT_FALSE(Range::open(0.5, 1).contains(0.5));
  EXPECT_TRUE(Range::open(0.5, 1).contains(0.7));
  EXPECT_FALSE(Range::open(0.5, 1).contains(std::nan("")));
  EXPECT_TRUE(Range::aboveUpTo(0, 100).contains(100));
  EXPECT_FALSE(Range::above(0).contains(0));
  EXPECT_TRUE(Range::any().contains(-1e300));
  EXPECT_EQ(Range::open(0.5, 1).text(), " in (0.5, 1)");
  EXPECT_EQ(Range::atLeast(0).text(), " >= 0");
}

TEST(OptionTableTest, CheckNamesTheFieldAndTheDeclarationsUseTheSameRange) {
  SonarOptions options;
  EXPECT_NO_THROW(checkOptions(options, SonarOptions::table(), "sonar."));
  options.prob_hit = 0.5;  // the open end
  try {
    checkOptions(options, SonarOptions::table(), "sonar.");
    FAIL() << "accepted prob_hit 0.5";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "sonar.prob_hit: expected a finite number in (0.5, 1), got 0.5");
  }
  EXPECT_THROW(checkOptions<ConfigError>(options, SonarOptions::table()), ConfigError);

  // The parameters declared from the table refuse what check() refuses, and --help says so.
  interfaces::Parameters p("sonar");
  p.setOverride("prob_hit:=0.5");
  SonarOptions declared;
  EXPECT_THROW(interfaces::declareOptions(p, "", SonarOptions::table(), declared, true),
               interfaces::ParameterError);
  interfaces::Parameters q("sonar");
  q.setOverride("range:=100");
  interfaces::declareOptions(q, "", SonarOptions::table(), declared, true);
  EXPECT_EQ(declared.range, 100);
  const std::string help = q.describe();
  const std::string range = help.substr(help.find("range:"));
  EXPECT_NE(range.find("min_exclusive: true"), std::string::npos) << help;
  EXPECT_EQ(range.find("max_exclusive"), std::string::npos) << help;  // (0, 100]: max allowed
}

}  // namespace
}  // namespace auv::config
