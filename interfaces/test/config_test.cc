// auv_config: the one exit-code rule of every `auv` command and the strict YAML reader that
// names file and field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include "auv/config/errors.h"
#include "auv/config/option_table.h"
#include "auv/config/spelling.h"
#include "auv/config/state_file.h"
#include "auv/config/yaml_scalars.h"
#include "auv/config/yaml_section.h"
#include "auv/interfaces/option_parameters.h"
#include "auv/interfaces/parameters.h"

namespace auv::config {
namespace {

TEST(StateFile, ReplacesTheFileWholeAndLeavesNoTemporary) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("auv_state_file_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::filesystem::path file = dir / "sub" / "state.yaml";
  writeFileAtomically(file, "first: 1\n");
  writeFileAtomically(file, "second: 2\n");
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "second: 2\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "sub" / "state.yaml.tmp"));
  // A folder that cannot be created is named.
  try {
    writeFileAtomically(file / "below_a_file", "x");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("state.yaml"), std::string::npos) << error.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(StateFile, LaunchIdIsTheLaunchsEnvironment) {
  ::setenv("AUV_LAUNCH_ID", "abc123", 1);
  EXPECT_EQ(launchId(), "abc123");
  ::unsetenv("AUV_LAUNCH_ID");
  EXPECT_EQ(launchId(), "");
}

TEST(ExitCodeRule, InputErrorsAreTwoAndFailuresOne) {
  EXPECT_EQ(exitCodeFor(ConfigError("x")), 2);
  EXPECT_EQ(exitCodeFor(interfaces::ParameterError("rate: expected > 0")), 2);
  EXPECT_EQ(exitCodeFor(std::invalid_argument("an options check()")), 2);
  EXPECT_EQ(exitCodeFor(RuntimeFailure("the peer vanished")), 1);
  EXPECT_EQ(exitCodeFor(std::runtime_error("anything else")), 1);
  EXPECT_EQ(exitCodeFor(std::bad_alloc()), 1);
}

TEST(YamlSectionTest, ReadsStrictlyAndNamesFileAndField) {
  const YamlSection root(
      YAML::Load("sonar: {range: far, beams: 0x10, on: yes, step: 2, count: \"5\", big: 1_000}"),
      "", "site.yaml");
  const YamlSection sonar = root.child("sonar");
  double range = 0;
  try {
    sonar.read("range", range, 0.0);
    FAIL() << "accepted 'far'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("site.yaml: sonar.range"), std::string::npos) << e.what();
  }
  int beams = 0;
  sonar.read("beams", beams);  // YAML 1.2 core: 0x10 is the integer 16 (as in parameter files)
  EXPECT_EQ(beams, 16);
  bool on = false;
  EXPECT_THROW(sonar.read("on", on), ConfigError);  // YAML 1.2: yes is not a boolean
  double step = 0;
  EXPECT_THROW(sonar.read("step", step, 0.0, 1.0), ConfigError);  // out of range
  int count = 0;
  try {
    sonar.read("count", count);  // a quoted scalar is a string
    FAIL() << "accepted \"5\"";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "site.yaml: sonar.count: expected an integer, got \"5\" (a quoted string)");
  }
  EXPECT_THROW(sonar.read("big", count), ConfigError);  // YAML 1.1 digit separators
  try {
    sonar.rejectUnknownKeys({"range", "beams", "on", "stop", "count", "big"});
    FAIL() << "accepted 'step'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'stop'"), std::string::npos) << e.what();
  }
  double absent = 7;
  sonar.read("absent", absent);
  EXPECT_EQ(absent, 7);  // defaults stay
}

TEST(YamlSectionTest, ListElementsAreNamedAndKeysAreChecked) {
  const YamlSection root(YAML::Load("a: [1, two, 3]\nb: 1\nb: 2\n"), "", "f.yaml");
  Eigen::Vector3d point;
  try {
    root.read("a", point);
    FAIL() << "accepted 'two'";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "f.yaml: a[1]: expected a finite number, got 'two'");
  }
  try {
    root.rejectUnknownKeys({"a", "b"});
    FAIL() << "accepted a duplicate key";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "f.yaml: b: duplicate key");
  }
}

// The one scalar rule: YamlSection (scenarios, missions), parameter files and the reconstruction
// options agree on every spelling, because they call the same functions.
TEST(ScalarRuleTest, Yaml12CoreSchemaEverywhere) {
  EXPECT_EQ(parseBool("True"), true);
  EXPECT_EQ(parseBool("FALSE"), false);
  for (const char* word : {"yes", "no", "on", "off", "y", "n", "1", "0", "tRUE", ""}) {
    EXPECT_FALSE(parseBool(word)) << word;
  }
  EXPECT_EQ(parseInteger("0x1F"), 31);
  EXPECT_EQ(parseInteger("0o17"), 15);
  EXPECT_EQ(parseInteger("-9223372036854775808"), std::numeric_limits<int64_t>::min());
  for (const char* text : {"1_000", "0b101", "-0x10", "1e3", "1.0", "0x", "9223372036854775808"}) {
    EXPECT_FALSE(parseInteger(text)) << text;
  }
  EXPECT_EQ(parseNumber("2.5E+2"), 250.0);
  EXPECT_EQ(parseNumber(".5"), 0.5);
  EXPECT_EQ(parseNumber("0x10"), 16.0);
  EXPECT_EQ(parseNumber("-.inf"), -std::numeric_limits<double>::infinity());
  for (const char* text : {"inf", "nan", "1,5", "0x1p3", " 1", "1 ", "1:30", "e5", "."}) {
    EXPECT_FALSE(parseNumber(text)) << text;
  }

  // The same text through a YamlSection and a parameter file: accepted or refused alike.
  for (const std::string text :
       {"3", "0x10", "0o7", "+2.5", "1e3", "1_000", "yes", "\"4\"", ".nan", "inf", "true", "010"}) {
    SCOPED_TRACE(text);
    const YamlSection section(YAML::Load("x: " + text), "", "f.yaml");
    double from_section = 0;
    bool section_ok = true;
    try {
      section.read("x", from_section);
    } catch (const ConfigError&) {
      section_ok = false;
    }
    interfaces::Parameters p("n");
    p.loadYaml("n: {x: " + text + "}\n", "p.yaml");
    double from_parameters = 0;
    bool parameters_ok = true;
    try {
      from_parameters = p.declare("x", 0.0);
    } catch (const interfaces::ParameterError&) {
      parameters_ok = false;
    }
    if (text == ".nan") {  // a number for both; YamlSection refuses it as not finite
      EXPECT_FALSE(section_ok);
      EXPECT_TRUE(parameters_ok);
      continue;
    }
    EXPECT_EQ(section_ok, parameters_ok);
    if (section_ok && parameters_ok) EXPECT_EQ(from_section, from_parameters);
  }
}

TEST(SpellingTest, OneSuggestionRule) {
  EXPECT_EQ(editDistance("rnage", "range"), 1u);
  EXPECT_EQ(closestMatch("rnage", {"range", "rate"}), "range");
  EXPECT_EQ(closestMatch("xyz", {"range", "rate"}), "");  // too far: no suggestion
  EXPECT_EQ(suggestionDistance("ab"), 2u);
  EXPECT_EQ(suggestionDistance("goal_tolerence"), 4u);
  EXPECT_EQ(closestMatch("goal_tolerence", {"goal", "goal_tolerance"}), "goal_tolerance");
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
    const std::string what = e.what();  // file:line:column, as parameter and launch files
    EXPECT_EQ(what.rfind(file.string() + ":", 0), 0u) << what;
    EXPECT_NE(what.find(": malformed YAML: "), std::string::npos) << what;
    EXPECT_EQ(what.find(file.string() + ": line"), std::string::npos) << what;
  }
  {
    std::ofstream out(file);  // empty
  }
  EXPECT_THROW(loadYamlFile(file.string()), ConfigError);
  EXPECT_FALSE(loadYamlFile(file.string(), true).has("a"));  // allowed: no settings
  EXPECT_THROW(loadYamlText("- a\n", "list.yaml"), ConfigError);
  std::filesystem::remove(file);
  EXPECT_THROW(loadYamlFile(file.string()), ConfigError);  // missing: named, exit code 2
}

/// The message of the ConfigError loadYamlText throws for `text` ("" if none).
std::string loadError(const std::string& text) {
  try {
    loadYamlText(text, "aliases.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(LoadYamlTest, AliasesAreReadButNeverIntoACycleOrAnExplosion) {
  // Aliases as YAML has them: shared scalars and collections.
  const YAML::Node shared = loadYaml("a: &x [1, 2]\nb: *x\nc: &s text\nd: [*s, *x]\n");
  EXPECT_EQ(shared["b"][1].as<int>(), 2);
  EXPECT_EQ(shared["d"][0].as<std::string>(), "text");
  EXPECT_EQ(shared["d"][1].size(), 2u);
  // An alias inside the node it refers to: yaml-cpp makes a node that contains itself, and
  // every walk of it (a message showing the value, a launch file's substitutions) overflowed
  // the stack. Refused where the alias is, like a syntax error.
  for (const std::string cycle : {"&a [*a]\n", "a: &a {b: *a}\n", "a: &a [1, {b: [*a]}]\n",
                                  "&a {*a : 1}\n", "a: &a [&b [*a]]\n"}) {
    SCOPED_TRACE(cycle);
    EXPECT_THROW(loadYaml(cycle), YAML::ParserException);
  }
  const std::string cycle = loadError("x: 1\nname: &a [1, *a]\n");
  EXPECT_NE(cycle.find("aliases.yaml:2:"), std::string::npos) << cycle;
  EXPECT_NE(cycle.find("malformed YAML: an alias inside the node it refers to"), std::string::npos)
      << cycle;
  // Aliases of aliases: `lines` lines that stand for 10^lines nodes.
  const auto laughs = [](int lines) {
    std::string text = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
    for (int i = 1; i < lines; ++i) {
      const std::string previous = "*l" + std::to_string(i - 1);
      text += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
      for (int j = 0; j < 10; ++j) text += (j ? ", " : "") + previous;
      text += "]\n";
    }
    return text;
  };
  const std::string exploded = loadError(laughs(10));  // the end of any walk or message
  EXPECT_NE(exploded.find("aliases.yaml:"), std::string::npos) << exploded;
  EXPECT_NE(exploded.find("stand for more than 10000 nodes"), std::string::npos) << exploded;
  EXPECT_THROW(loadYaml(laughs(4)), YAML::ParserException);                 // 12330 nodes
  EXPECT_EQ(loadYaml(laughs(3))["l2"][9][9][9].as<std::string>(), "x");  // 1220 nodes: fine
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
  // range is (0, 100]: its min is excluded, its max allowed (prob_hit excludes both ends).
  const YAML::Node help = YAML::Load(q.describe());
  EXPECT_TRUE(help["range"]["min_exclusive"].as<bool>());
  EXPECT_FALSE(help["range"]["max_exclusive"]);
  EXPECT_TRUE(help["prob_hit"]["max_exclusive"].as<bool>());
}

// One table of every kind: integers keep their C++ type, bools and strings (with choices) are
// declared from the same entries.
struct QueueOptions {
  double rate = 2.0;
  int64_t length = 500;
  std::size_t capacity = 2000;
  uint32_t chunk = 4096;
  int retries = 3;
  bool clear_on_start = true;
  std::string objective = "visibility";
  std::string frame = "world";
  std::vector<std::string> sensors = {"sonar"};
  static const OptionTable<QueueOptions>& table() {
    static const OptionTable<QueueOptions> kTable = {
        {"rate", &QueueOptions::rate, "update rate", "Hz", Range::above(0)},
        {"length", &QueueOptions::length, "beams kept", "beams", Range::closed(0, 100000)},
        {"capacity", &QueueOptions::capacity, "poses kept", "poses", Range::closed(2, 1e6)},
        {"chunk", &QueueOptions::chunk, "chunk cap", "B", Range::closed(4096, 1 << 24)},
        {"retries", &QueueOptions::retries, "attempts", "", Range::closed(1, 10)},
        {"clear_on_start", &QueueOptions::clear_on_start, "start empty"},
        {"objective", &QueueOptions::objective, "cost", "", {}, {"visibility", "path_length"}},
        {"frame", &QueueOptions::frame, "frame of the map"},
        {"sensors", &QueueOptions::sensors, "sensors mapped", "", {}, {"sonar", "camera"}}};
    return kTable;
  }
};

TEST(OptionTableTest, IntegersBoolsAndStringsAreCheckedFromTheSameTable) {
  QueueOptions options;
  EXPECT_NO_THROW(checkOptions(options, QueueOptions::table(), "queue."));
  auto message = [](const QueueOptions& o) {
    try {
      checkOptions(o, QueueOptions::table(), "queue.");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  QueueOptions o = options;
  o.length = -1;
  EXPECT_EQ(message(o), "queue.length: expected an integer in [0, 100000] beams, got -1");
  o = options;
  o.capacity = 1;
  EXPECT_EQ(message(o), "queue.capacity: expected an integer in [2, 1000000] poses, got 1");
  o = options;
  o.retries = 11;
  EXPECT_EQ(message(o), "queue.retries: expected an integer in [1, 10], got 11");
  o = options;
  o.objective = "shortest";
  EXPECT_EQ(message(o), "queue.objective: expected one of visibility, path_length, got 'shortest'");
  o = options;
  o.frame = "anything";  // no choices: any string
  o.clear_on_start = false;
  EXPECT_EQ(message(o), "");
  o.sensors = {"camera", "laser"};
  EXPECT_EQ(message(o), "queue.sensors: expected each one of sonar, camera, got 'laser'");
  EXPECT_EQ(QueueOptions::table()[1].member<int64_t>(), &QueueOptions::length);
}

TEST(OptionTableTest, DeclaredParametersHaveTheMembersTypesRangesAndChoices) {
  QueueOptions declared;
  interfaces::Parameters q("queue");
  q.setOverride("length:=20");
  q.setOverride("capacity:=30");
  q.setOverride("chunk:=8192");
  q.setOverride("clear_on_start:=false");
  q.setOverride("objective:=path_length");
  q.setOverride("sensors:=[camera, sonar]");
  interfaces::declareOptions(q, "", QueueOptions::table(), declared, true);
  EXPECT_EQ(declared.length, 20);
  EXPECT_EQ(declared.capacity, 30u);
  EXPECT_EQ(declared.chunk, 8192u);
  EXPECT_FALSE(declared.clear_on_start);
  EXPECT_EQ(declared.objective, "path_length");
  EXPECT_EQ(declared.sensors, (std::vector<std::string>{"camera", "sonar"}));
  EXPECT_EQ(q.get<int64_t>("retries"), 3);
  EXPECT_EQ(q.get<std::string>("frame"), "world");
  const YAML::Node help = YAML::Load(q.describe());
  EXPECT_EQ(help["length"]["type"].as<std::string>(), "integer");
  EXPECT_EQ(help["capacity"]["min"].as<int64_t>(), 2);
  EXPECT_EQ(help["capacity"]["max"].as<int64_t>(), 1000000);
  EXPECT_EQ(help["chunk"]["unit"].as<std::string>(), "B");
  EXPECT_EQ(help["clear_on_start"]["type"].as<std::string>(), "bool");
  EXPECT_EQ(help["objective"]["choices"].size(), 2u);
  EXPECT_TRUE(help["frame"]["read_only"].as<bool>());

  // What check() refuses, the declaration refuses: out of range, a wrong choice, a wrong type.
  for (const char* bad : {"length:=100001", "capacity:=1", "chunk:=-1", "objective:=shortest",
                          "retries:=1.5", "clear_on_start:=1", "sensors:=[laser]"}) {
    interfaces::Parameters r("queue");
    r.setOverride(bad);
    QueueOptions refused;
    EXPECT_THROW(interfaces::declareOptions(r, "", QueueOptions::table(), refused, true),
                 interfaces::ParameterError)
        << bad;
  }
}

}  // namespace
}  // namespace auv::config
