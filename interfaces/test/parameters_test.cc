#include "auv/interfaces/parameters.h"

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

namespace auv::interfaces {
namespace {

// A check on a message, for EXPECT_TEXT (plain GoogleTest, no gmock needed).
struct TextMatcher {
  std::string description;                        // e.g. "contains 'abc'"
  std::function<bool(const std::string&)> check;  // true if the text matches
};

TextMatcher HasSubstr(const std::string& part) {
  return {"contains '" + part + "'",
          [part](const std::string& text) { return text.find(part) != std::string::npos; }};
}

TextMatcher StartsWith(const std::string& prefix) {
  return {"starts with '" + prefix + "'",
          [prefix](const std::string& text) { return text.rfind(prefix, 0) == 0; }};
}

TextMatcher MatchesRegex(const std::string& pattern) {
  return {"matches /" + pattern + "/", [pattern](const std::string& text) {
            return std::regex_match(text, std::regex(pattern));
          }};
}

TextMatcher Not(const TextMatcher& matcher) {
  return {"not " + matcher.description,
          [matcher](const std::string& text) { return !matcher.check(text); }};
}

::testing::AssertionResult textMatches(const std::string& text, const TextMatcher& matcher) {
  if (matcher.check(text)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' " << matcher.description << " is false";
}

#define EXPECT_TEXT(text, matcher) EXPECT_TRUE(textMatches((text), (matcher)))

// Runs `f`, expects a ParameterError and returns its message.
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ParameterError, got other exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected ParameterError, nothing thrown";
  return "";
}

// Writes `text` to a fresh file under the test temp dir and returns its path.
std::string writeTempFile(const std::string& file_name, const std::string& text) {
  const std::string path = ::testing::TempDir() + file_name;
  std::ofstream(path) << text;
  return path;
}

ParameterDescriptor rangeDescriptor(double min, double max, const std::string& unit = "") {
  ParameterDescriptor d;
  d.min = min;
  d.max = max;
  d.unit = unit;
  return d;
}

// ---------------------------------------------------------------------------------------------
// Loading and types

TEST(ParametersTest, DefaultsApplyWhenNothingIsConfigured) {
  Parameters p("planner");
  EXPECT_EQ(p.node_name(), "planner");
  EXPECT_FALSE(p.has("rate"));
  EXPECT_DOUBLE_EQ(p.declare("rate", 10.0), 10.0);
  EXPECT_EQ(p.declare("mode", "fast"), "fast");  // string literal default
  EXPECT_EQ(p.declare<int>("retries", 3), 3);
  EXPECT_TRUE(p.has("rate"));
  EXPECT_DOUBLE_EQ(p.get<double>("rate"), 10.0);
  EXPECT_EQ(p.get<std::string>("mode"), "fast");
  EXPECT_EQ(p.type("retries"), ParameterType::INTEGER);
  EXPECT_EQ(p.names(), (std::vector<std::string>{"rate", "mode", "retries"}));
}

TEST(ParametersTest, LoadsEveryTypeFromTheNodeSection) {
  Parameters p("planner");
  p.loadYaml(R"(
planner:
  enabled: false
  retries: 7
  big: -9223372036854775808
  mask: 0xff
  rate: 2.5
  whole: 4            # an integer is accepted for a double
  tiny: 1e-3
  limit: .inf
  name: survey_a
  number_as_string: 0042
  flags: [true, false, True]
  ids: [1, -2, 3]
  weights: [0.5, 1, 2e2]
  frames: [base_link, "camera"]
  empty: []
)",
             "params.yaml");
  EXPECT_EQ(p.declare("enabled", true), false);
  EXPECT_EQ(p.declare<int>("retries", 0), 7);
  EXPECT_EQ(p.declare<int64_t>("big", 0), std::numeric_limits<int64_t>::min());
  EXPECT_EQ(p.declare<uint32_t>("mask", 0u), 255u);
  EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 2.5);
  EXPECT_DOUBLE_EQ(p.declare("whole", 0.0), 4.0);
  EXPECT_DOUBLE_EQ(p.declare("tiny", 0.0), 1e-3);
  EXPECT_EQ(p.declare("limit", 0.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(p.declare("name", "default"), "survey_a");
  EXPECT_EQ(p.declare("number_as_string", ""), "0042");  // strings keep the text as written
  EXPECT_EQ(p.declare("flags", std::vector<bool>{}), (std::vector<bool>{true, false, true}));
  EXPECT_EQ(p.declare("ids", std::vector<int>{}), (std::vector<int>{1, -2, 3}));
  EXPECT_EQ(p.declare("weights", std::vector<double>{}), (std::vector<double>{0.5, 1.0, 200.0}));
  EXPECT_EQ(p.declare("frames", std::vector<std::string>{}),
            (std::vector<std::string>{"base_link", "camera"}));
  EXPECT_EQ(p.declare("empty", std::vector<double>{9.0}), std::vector<double>{});
  EXPECT_EQ(p.getValue("ids"), ParameterValue(std::vector<int64_t>{1, -2, 3}));
  EXPECT_TRUE(p.unusedOverrides().empty());
}

TEST(ParametersTest, LoadFileReadsARealFileAndNamesItInErrors) {
  const std::string path = writeTempFile("load_file.yaml", "planner:\n  range: abc\n  rate: 5\n");
  Parameters p("planner");
  p.loadFile(path);
  EXPECT_DOUBLE_EQ(p.declare("rate", 1.0), 5.0);
  EXPECT_EQ(errorOf([&] { p.declare("range", 1.0); }),
            "parameter 'range' in " + path + ": expected a number, got 'abc'");
}

TEST(ParametersTest, LoadFileReportsAnUnreadableFile) {
  Parameters p("planner");
  const std::string path = ::testing::TempDir() + "does_not_exist.yaml";
  const std::string message = errorOf([&] { p.loadFile(path); });
  EXPECT_TEXT(message, StartsWith(path + ": cannot read parameter file"));
  EXPECT_EQ(errorOf([&] { p.loadFile(::testing::TempDir()); }),
            ::testing::TempDir() + ": cannot read parameter file: is a directory");
}

TEST(ParametersTest, NestedMapsFlattenToDottedNames) {
  Parameters p("planner");
  p.loadYaml(R"(
planner:
  planner:
    range: 2.0
    limits: {speed: 0.5, depth: {max: 30}}
  camera.exposure: 0.01   # dotted keys work too
)",
             "params.yaml");
  EXPECT_DOUBLE_EQ(p.declare("planner.range", 1.0), 2.0);
  EXPECT_DOUBLE_EQ(p.declare("planner.limits.speed", 1.0), 0.5);
  EXPECT_EQ(p.declare<int>("planner.limits.depth.max", 10), 30);
  EXPECT_DOUBLE_EQ(p.declare("camera.exposure", 1.0), 0.01);
  EXPECT_TRUE(p.unusedOverrides().empty());
}

TEST(ParametersTest, AcceptsRos2FilesWithRosParametersLevel) {
  Parameters p("/planner");
  p.loadYaml("/planner:\n  ros__parameters:\n    rate: 3.0\n", "ros.yaml");
  EXPECT_DOUBLE_EQ(p.declare("rate", 1.0), 3.0);
}

TEST(ParametersTest, IgnoresOtherNodesSectionsAndEmptyFiles) {
  Parameters p("planner");
  p.loadYaml("", "empty.yaml");
  p.loadYaml("# only a comment\n", "comment.yaml");
  p.loadYaml("mapper:\n  rate: 99.0\n  bogus: x\nplanner:\n", "other.yaml");
  EXPECT_DOUBLE_EQ(p.declare("rate", 1.0), 1.0);
  EXPECT_TRUE(p.unusedOverrides().empty());
}

// ---------------------------------------------------------------------------------------------
// Precedence

TEST(ParametersTest, WildcardSectionsApplyToEveryNode) {
  for (const std::string wildcard : {"/**", "\"*\""}) {
    Parameters p("planner");
    p.loadYaml(wildcard + ":\n  use_sim_time: true\n", "common.yaml");
    EXPECT_TRUE(p.declare("use_sim_time", false)) << wildcard;
  }
}

TEST(ParametersTest, NodeSectionBeatsWildcardRegardlessOfOrder) {
  {
    Parameters p("planner");
    p.loadYaml("planner: {rate: 2.0}\n/**: {rate: 9.0, depth: 4.0}\n", "one.yaml");
    EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 2.0);
    EXPECT_DOUBLE_EQ(p.declare("depth", 0.0), 4.0);  // only in the wildcard
  }
  {
    Parameters p("planner");
    p.loadYaml("planner: {rate: 2.0}\n", "first.yaml");
    p.loadYaml("/**: {rate: 9.0}\n", "later.yaml");  // later wildcard does not beat node section
    EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 2.0);
    EXPECT_EQ(p.describe().find("source: later.yaml"), std::string::npos);
  }
}

TEST(ParametersTest, LaterLoadsOverrideEarlierOnes) {
  Parameters p("planner");
  p.loadYaml("planner: {rate: 2.0, depth: 5.0}\n/**: {gain: 1.0}\n", "base.yaml");
  p.loadYaml("planner: {rate: 3.0}\n/**: {gain: 2.0}\n", "mission.yaml");
  EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 3.0);
  EXPECT_DOUBLE_EQ(p.declare("depth", 0.0), 5.0);
  EXPECT_DOUBLE_EQ(p.declare("gain", 0.0), 2.0);
}

TEST(ParametersTest, CommandLineOverridesBeatFilesLoadedBeforeAndAfter) {
  Parameters p("planner");
  p.loadYaml("planner: {rate: 2.0, mode: slow}\n", "base.yaml");
  p.setOverride("rate:=4.5");
  p.setOverride("weights:=[1, 2.5]");
  p.setOverride("mode := fast");  // spaces around the name are trimmed
  p.loadYaml("planner: {rate: 7.0}\n", "late.yaml");
  EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 4.5);
  EXPECT_EQ(p.declare("weights", std::vector<double>{}), (std::vector<double>{1.0, 2.5}));
  EXPECT_EQ(p.declare("mode", "x"), "fast");
  EXPECT_TEXT(p.describe(), HasSubstr("source: command line (-p)"));
}

TEST(ParametersTest, LaterCommandLineOverrideWins) {
  Parameters p("planner");
  p.setOverride("rate:=1.0");
  p.setOverride("rate:=2.0");
  EXPECT_DOUBLE_EQ(p.declare("rate", 0.0), 2.0);
}

TEST(ParametersTest, LoadingAfterDeclarationIsAnError) {
  Parameters p("planner");
  p.declare("rate", 1.0);
  EXPECT_TEXT(errorOf([&] { p.loadYaml("planner: {rate: 2.0}\n", "late.yaml"); }),
              HasSubstr("parameter 'rate' in late.yaml: already declared"));
  EXPECT_TEXT(errorOf([&] { p.setOverride("rate:=3.0"); }),
              HasSubstr("parameter 'rate' in command line (-p): already declared"));
  EXPECT_DOUBLE_EQ(p.get<double>("rate"), 1.0);
}

// ---------------------------------------------------------------------------------------------
// Type errors

// Declares `name` with `declare_fn` after loading "planner: {<name>: <yaml_value>}".
template <class T>
std::string loadError(const std::string& yaml_value, const T& default_value,
                      const ParameterDescriptor& descriptor = {}) {
  Parameters p("planner");
  p.loadYaml("planner:\n  x: " + yaml_value + "\n", "/path/params.yaml");
  return errorOf([&] { p.declare<T>("x", default_value, descriptor); });
}

TEST(ParametersTest, TypeErrorsNameParameterFileExpectationAndValue) {
  const std::string prefix = "parameter 'x' in /path/params.yaml: ";
  EXPECT_EQ(loadError("abc", 1.0), prefix + "expected a number, got 'abc'");
  EXPECT_EQ(loadError("1.5", 1), prefix +
                                     "expected an integer in [-2147483648, 2147483647], "
                                     "got '1.5'");
  EXPECT_EQ(loadError<int64_t>("1.0", 1), prefix + "expected an integer, got '1.0'");
  EXPECT_EQ(loadError<int64_t>("1e3", 1), prefix + "expected an integer, got '1e3'");
  EXPECT_EQ(loadError<int64_t>("\"5\"", 1),
            prefix + "expected an integer, got \"5\" (a quoted string)");
  EXPECT_EQ(loadError<int64_t>("99999999999999999999", 1),
            prefix + "expected an integer, got '99999999999999999999'");
  EXPECT_EQ(loadError("\"2.5\"", 1.0), prefix + "expected a number, got \"2.5\" (a quoted string)");
  EXPECT_EQ(loadError("nan", 1.0), prefix + "expected a number, got 'nan'");  // YAML says .nan
  EXPECT_EQ(loadError("yes", true), prefix + "expected a boolean (true or false), got 'yes'");
  EXPECT_EQ(loadError("1", true), prefix + "expected a boolean (true or false), got '1'");
  EXPECT_EQ(loadError("\"true\"", true),
            prefix + "expected a boolean (true or false), got \"true\" (a quoted string)");
  EXPECT_EQ(loadError("", 1.0), prefix + "expected a number, got null (empty value)");
  EXPECT_EQ(loadError("", std::string("s")), prefix + "expected a string, got null (empty value)");
  EXPECT_EQ(loadError("[1, 2]", 1.0), prefix + "expected a number, got '[1, 2]'");
  EXPECT_EQ(loadError("3", std::vector<int64_t>{}),
            prefix + "expected a list of integers, got '3'");
  EXPECT_EQ(loadError("[1, abc, 3]", std::vector<double>{}),
            prefix + "expected a list of numbers, got '[1, abc, 3]' (element 1: 'abc')");
  EXPECT_EQ(loadError("[true, no]", std::vector<bool>{}),
            prefix +
                "expected a list of booleans (true or false), got '[true, no]' "
                "(element 1: 'no')");
  EXPECT_EQ(loadError("[[1], 2]", std::vector<int64_t>{}),
            prefix + "expected a list of integers, got '[[1], 2]' (element 0: '[1]')");
}

TEST(ParametersTest, MapValueForScalarIsNotFlattenedIntoIt) {
  // "x: {a: 1}" defines x.a, not x: x keeps its default and x.a is reported as unused.
  Parameters p("planner");
  p.loadYaml("planner:\n  x: {a: 1}\n", "params.yaml");
  EXPECT_DOUBLE_EQ(p.declare("x", 1.0), 1.0);
  EXPECT_EQ(p.unusedOverrides(),
            (std::vector<std::string>{"'x.a' from params.yaml (did you mean 'x'?)"}));
}

TEST(ParametersTest, StringsAcceptAnyScalarAsWritten) {
  Parameters p("planner");
  p.loadYaml("planner: {a: 5, b: true, c: \"quoted: yes\", d: 1.50}\n", "params.yaml");
  EXPECT_EQ(p.declare("a", ""), "5");
  EXPECT_EQ(p.declare("b", ""), "true");
  EXPECT_EQ(p.declare("c", ""), "quoted: yes");
  EXPECT_EQ(p.declare("d", ""), "1.50");
}

TEST(ParametersTest, BooleansAcceptOnlyYaml12Spellings) {
  Parameters p("planner");
  p.loadYaml("planner: {a: True, b: FALSE, c: true}\n", "params.yaml");
  EXPECT_TRUE(p.declare("a", false));
  EXPECT_FALSE(p.declare("b", true));
  EXPECT_TRUE(p.declare("c", false));
  for (const std::string bad : {"yes", "no", "on", "off", "0", "y"}) {
    EXPECT_TEXT(loadError(bad, false), HasSubstr("got '" + bad + "'")) << bad;
  }
}

TEST(ParametersTest, NumbersFollowYaml12CoreSchema) {
  Parameters p("planner");
  p.loadYaml(
      "planner: {h: 0x1F, o: 0o17, n: -12, pos: +3, f: -.5, e: 2.5E+2, i: -.inf, nan: .nan}\n",
      "params.yaml");
  EXPECT_EQ(p.declare<int64_t>("h", 0), 31);
  EXPECT_EQ(p.declare<int64_t>("o", 0), 15);
  EXPECT_EQ(p.declare<int64_t>("n", 0), -12);
  EXPECT_EQ(p.declare<int64_t>("pos", 0), 3);
  EXPECT_DOUBLE_EQ(p.declare("f", 0.0), -0.5);
  EXPECT_DOUBLE_EQ(p.declare("e", 0.0), 250.0);
  EXPECT_EQ(p.declare("i", 0.0), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(p.declare("nan", 0.0)));
  for (const std::string bad : {"1_000", "0x", "-0x10", "1.", "abc", "1e", "e5", "inf", "1,5"}) {
    EXPECT_TEXT(loadError<int64_t>(bad, 0), HasSubstr("expected an integer")) << bad;
  }
  for (const std::string bad : {"1_000", "0x", "abc", "1e", "e5", "inf", "1,5", ".", "+-1"}) {
    EXPECT_TEXT(loadError(bad, 0.0), HasSubstr("expected a number")) << bad;
  }
}

// ---------------------------------------------------------------------------------------------
// Ranges and choices

TEST(ParametersTest, RangeErrorsShowTheInclusiveRange) {
  const auto range = rangeDescriptor(0.1, 50.0, "m");
  const std::string prefix = "parameter 'x' in /path/params.yaml: ";
  EXPECT_EQ(loadError("abc", 1.0, range), prefix + "expected a number in [0.1, 50], got 'abc'");
  EXPECT_EQ(loadError("60", 1.0, range), prefix + "expected a number in [0.1, 50], got '60'");
  EXPECT_EQ(loadError("0.05", 1.0, range), prefix + "expected a number in [0.1, 50], got '0.05'");
  EXPECT_EQ(loadError(".nan", 1.0, range), prefix + "expected a number in [0.1, 50], got '.nan'");
  EXPECT_EQ(loadError("[1, 70]", std::vector<double>{}, range),
            prefix + "expected a list of numbers in [0.1, 50], got '[1, 70]' (element 1: '70')");
  ParameterDescriptor at_least;
  at_least.min = 1;
  EXPECT_EQ(loadError<int64_t>("0", 5, at_least), prefix + "expected an integer >= 1, got '0'");
  ParameterDescriptor at_most;
  at_most.max = 2.5;
  EXPECT_EQ(loadError("3", 1.0, at_most), prefix + "expected a number <= 2.5, got '3'");
  // Bounds are inclusive.
  Parameters p("planner");
  p.loadYaml("planner: {lo: 0.1, hi: 50}\n", "params.yaml");
  EXPECT_DOUBLE_EQ(p.declare("lo", 1.0, range), 0.1);
  EXPECT_DOUBLE_EQ(p.declare("hi", 1.0, range), 50.0);
}

TEST(ParametersTest, IntegerTypeRangeIsEnforced) {
  const std::string prefix = "parameter 'x' in /path/params.yaml: ";
  EXPECT_EQ(loadError<uint8_t>("300", 0), prefix + "expected an integer in [0, 255], got '300'");
  EXPECT_EQ(loadError<uint32_t>("-1", 0),
            prefix + "expected an integer in [0, 4294967295], got '-1'");
  EXPECT_EQ(loadError("[1, 256]", std::vector<uint8_t>{}),
            prefix + "expected a list of integers in [0, 255], got '[1, 256]' (element 1: '256')");
  // Descriptor and type range combine.
  EXPECT_EQ(loadError<uint16_t>("0", 1, rangeDescriptor(1, 1e9)),
            prefix + "expected an integer in [1, 65535], got '0'");
  Parameters p("planner");
  p.loadYaml("planner: {x: 4294967295}\n", "params.yaml");
  EXPECT_EQ(p.declare<uint32_t>("x", 0), 4294967295u);
}

TEST(ParametersTest, ChoicesRestrictStrings) {
  ParameterDescriptor modes;
  modes.choices = {"fast", "slow"};
  Parameters p("planner");
  p.setOverride("mode:=medium");
  EXPECT_EQ(errorOf([&] { p.declare("mode", "fast", modes); }),
            "parameter 'mode' in command line (-p): expected one of [fast, slow], got 'medium'");
  EXPECT_FALSE(p.has("mode"));  // a failed declaration declares nothing

  Parameters q("planner");
  q.loadYaml("planner: {mode: slow, modes: [fast, warp]}\n", "params.yaml");
  EXPECT_EQ(q.declare("mode", "fast", modes), "slow");
  EXPECT_EQ(errorOf([&] { q.declare("modes", std::vector<std::string>{}, modes); }),
            "parameter 'modes' in params.yaml: expected a list of strings, each one of "
            "[fast, slow], got '[fast, warp]' (element 1: 'warp')");
}

TEST(ParametersTest, InvalidDeclarationsThrow) {
  Parameters p("planner");
  EXPECT_EQ(errorOf([&] { p.declare("range", 100.0, rangeDescriptor(0.1, 50)); }),
            "parameter 'range': invalid default: expected a number in [0.1, 50], got '100'");
  EXPECT_TEXT(errorOf([&] { p.declare("a", 1.0, rangeDescriptor(5, 1)); }),
              HasSubstr("parameter 'a': invalid declaration: min 5 > max 1"));
  ParameterDescriptor choices;
  choices.choices = {"x"};
  EXPECT_TEXT(errorOf([&] { p.declare("b", 1.0, choices); }),
              HasSubstr("choices apply to strings"));
  EXPECT_TEXT(errorOf([&] { p.declare("c", "s", rangeDescriptor(0, 1)); }),
              HasSubstr("min/max apply to numbers"));
  EXPECT_TEXT(errorOf([&] { p.declare<int>("d", 1, rangeDescriptor(0.2, 0.8)); }),
              HasSubstr("no integer lies in the allowed range"));
  EXPECT_TEXT(errorOf([&] { p.declare("", 1.0); }), HasSubstr("invalid parameter name ''"));
  EXPECT_TEXT(errorOf([&] { p.declare("a..b", 1.0); }), HasSubstr("invalid parameter name"));
  EXPECT_TEXT(errorOf([&] { p.declare<uint64_t>("e", UINT64_MAX); }), HasSubstr("does not fit"));
  EXPECT_TRUE(p.names().empty());
}

// ---------------------------------------------------------------------------------------------
// Redeclaration and get()

TEST(ParametersTest, RedeclaringWithAnotherTypeThrowsAndWithTheSameTypeReturnsCurrentValue) {
  Parameters p("planner");
  p.loadYaml("planner: {rate: 4.0}\n", "params.yaml");
  EXPECT_DOUBLE_EQ(p.declare("rate", 1.0), 4.0);
  EXPECT_DOUBLE_EQ(p.declare("rate", 2.0), 4.0);
  EXPECT_EQ(errorOf([&] { p.declare<int>("rate", 1); }),
            "parameter 'rate' is already declared as double, cannot redeclare it as integer");
  EXPECT_TEXT(errorOf([&] { p.declare("rate", std::vector<double>{}); }),
              HasSubstr("cannot redeclare it as double_array"));
}

TEST(ParametersTest, GetThrowsForUndeclaredOrWrongType) {
  Parameters p("planner");
  p.declare<int>("count", 300);
  EXPECT_EQ(errorOf([&] { p.get<double>("missing"); }),
            "parameter 'missing' of node 'planner' is not declared");
  EXPECT_EQ(errorOf([&] { p.get<double>("count"); }),
            "parameter 'count' is declared as integer, requested as double");
  EXPECT_TEXT(errorOf([&] { p.get<std::vector<int64_t>>("count"); }),
              HasSubstr("requested as integer_array"));
  EXPECT_EQ(p.get<int64_t>("count"), 300);
  EXPECT_EQ(p.get<uint16_t>("count"), 300u);  // integer types are interchangeable if it fits
  EXPECT_EQ(errorOf([&] { p.get<uint8_t>("count"); }),
            "parameter 'count': value 300 does not fit in the requested type [0, 255]");
  EXPECT_THROW(p.getValue("missing"), ParameterError);
  EXPECT_THROW(p.type("missing"), ParameterError);
}

// ---------------------------------------------------------------------------------------------
// Runtime set()

TEST(ParametersTest, SetValidatesTypeAndRange) {
  Parameters p("planner");
  p.declare("range", 2.0, rangeDescriptor(0.1, 50, "m"));
  p.declare<int>("count", 1);
  ParameterDescriptor modes;
  modes.choices = {"fast", "slow"};
  p.declare("mode", "fast", modes);
  p.declare("weights", std::vector<double>{1.0}, rangeDescriptor(0, 1));

  auto r = p.set("range", 60.0);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'range': expected a number in [0.1, 50], got '60'");
  r = p.set("range", std::string("abc"));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'range': expected a number in [0.1, 50], got string 'abc'");
  r = p.set("count", 1.5);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason,
            "parameter 'count': expected an integer in [-2147483648, 2147483647], got "
            "double '1.5'");
  r = p.set("count", int64_t{1} << 40);
  EXPECT_FALSE(r.ok);
  EXPECT_TEXT(r.reason, HasSubstr("got '1099511627776'"));
  r = p.set("mode", "medium");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'mode': expected one of [fast, slow], got 'medium'");
  r = p.set("weights", std::vector<double>{0.5, 2.0});
  EXPECT_FALSE(r.ok);
  EXPECT_TEXT(r.reason, HasSubstr("got '[0.5, 2]' (element 1: '2')"));
  r = p.set("nope", 1.0);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'nope' of node 'planner' is not declared; cannot set it to '1'");

  // Nothing changed.
  EXPECT_DOUBLE_EQ(p.get<double>("range"), 2.0);
  EXPECT_EQ(p.get<int>("count"), 1);
  EXPECT_EQ(p.get<std::string>("mode"), "fast");

  EXPECT_TRUE(p.set("range", 3.5).ok);
  EXPECT_DOUBLE_EQ(p.get<double>("range"), 3.5);
  EXPECT_TRUE(p.set("range", int64_t{7}).ok);  // integer accepted for double
  EXPECT_DOUBLE_EQ(p.get<double>("range"), 7.0);
  EXPECT_TRUE(p.set("count", 42).ok);
  EXPECT_EQ(p.get<int>("count"), 42);
  EXPECT_TRUE(p.set("mode", "slow").ok);
  EXPECT_EQ(p.get<std::string>("mode"), "slow");
  EXPECT_TRUE(p.set("weights", std::vector<int64_t>{0, 1}).ok);
  EXPECT_EQ(p.get<std::vector<double>>("weights"), (std::vector<double>{0.0, 1.0}));
  EXPECT_TEXT(p.describe(), HasSubstr("source: set()"));
}

TEST(ParametersTest, SetFromYamlUsesFileConversionRules) {
  Parameters p("planner");
  p.declare("range", 2.0, rangeDescriptor(0.1, 50));
  p.declare("ids", std::vector<int64_t>{});
  EXPECT_TRUE(p.setFromYaml("range", "4").ok);
  EXPECT_DOUBLE_EQ(p.get<double>("range"), 4.0);
  EXPECT_TRUE(p.setFromYaml("ids", "[3, 4]").ok);
  EXPECT_EQ(p.get<std::vector<int>>("ids"), (std::vector<int>{3, 4}));
  auto r = p.setFromYaml("range", "abc");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'range': expected a number in [0.1, 50], got 'abc'");
  r = p.setFromYaml("range", "99");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'range': expected a number in [0.1, 50], got '99'");
  r = p.setFromYaml("ids", "[1, 2");
  EXPECT_FALSE(r.ok);
  EXPECT_TEXT(r.reason, StartsWith("parameter 'ids': malformed value '[1, 2'"));
  EXPECT_FALSE(p.setFromYaml("missing", "1").ok);
}

TEST(ParametersTest, ReadOnlyParametersRejectSetButAcceptFileValues) {
  ParameterDescriptor read_only;
  read_only.read_only = true;
  Parameters p("planner");
  p.loadYaml("planner: {frame: odom}\n", "params.yaml");
  EXPECT_EQ(p.declare("frame", "map", read_only), "odom");
  const auto r = p.set("frame", "base_link");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'frame' is read-only; cannot set it to 'base_link'");
  EXPECT_EQ(p.get<std::string>("frame"), "odom");
  EXPECT_TEXT(p.describe(), HasSubstr("read_only: true"));
}

TEST(ParametersTest, OnSetCallbacksCanVetoAndSeeNormalizedValues) {
  Parameters p("planner");
  p.declare("min_depth", 1.0);
  p.declare("max_depth", 10.0);
  std::vector<std::string> seen;
  p.onSet([&](const std::string& name, const ParameterValue& value) -> Parameters::SetResult {
    seen.push_back(name + "=" + toString(value) + ":" + toString(typeOf(value)));
    if (name == "min_depth" && std::get<double>(value) >= p.get<double>("max_depth")) {
      return {false,
              "min_depth must be below max_depth (" + toString(p.getValue("max_depth")) + ")"};
    }
    return {true, ""};
  });
  int second_calls = 0;
  p.onSet([&](const std::string&, const ParameterValue&) -> Parameters::SetResult {
    ++second_calls;
    return {true, ""};
  });

  const auto r = p.set("min_depth", 12.0);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason,
            "parameter 'min_depth' = '12' rejected: min_depth must be below max_depth "
            "(10)");
  EXPECT_DOUBLE_EQ(p.get<double>("min_depth"), 1.0);
  EXPECT_EQ(second_calls, 0);  // a veto stops the chain

  EXPECT_TRUE(p.set("min_depth", int64_t{3}).ok);  // callback sees the double 3
  EXPECT_DOUBLE_EQ(p.get<double>("min_depth"), 3.0);
  EXPECT_EQ(second_calls, 1);
  EXPECT_EQ(seen, (std::vector<std::string>{"min_depth=12:double", "min_depth=3:double"}));

  // Invalid values are rejected before callbacks run.
  EXPECT_FALSE(p.set("min_depth", "deep").ok);
  EXPECT_EQ(seen.size(), 2u);
}

TEST(ParametersTest, ThrowingCallbackRejectsTheValue) {
  Parameters p("planner");
  p.declare("gain", 1.0);
  p.onSet([](const std::string&, const ParameterValue&) -> Parameters::SetResult {
    throw std::runtime_error("boom");
  });
  const auto r = p.set("gain", 2.0);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.reason, "parameter 'gain' = '2' rejected: callback threw: boom");
  EXPECT_DOUBLE_EQ(p.get<double>("gain"), 1.0);
}

// ---------------------------------------------------------------------------------------------
// Unused overrides

TEST(ParametersTest, UnusedOverridesReportTyposWithClosestDeclaredName) {
  Parameters p("planner");
  p.loadYaml(R"(
/**:
  use_sim_time: true     # wildcard: other nodes may declare it, not reported
planner:
  planner:
    rnage: 3.0           # transposition of range
  max_sped: 2.0
  completely_unrelated: 1
  range: 5.0             # right leaf, wrong nesting
)",
             "/path/params.yaml");
  p.setOverride("max_speeed:=1.0");
  p.declare("planner.range", 1.0);
  p.declare("max_speed", 1.0);
  EXPECT_EQ(p.unusedOverrides(),
            (std::vector<std::string>{
                "'planner.rnage' from /path/params.yaml (did you mean 'planner.range'?)",
                "'max_sped' from /path/params.yaml (did you mean 'max_speed'?)",
                "'completely_unrelated' from /path/params.yaml",
                "'range' from /path/params.yaml (did you mean 'planner.range'?)",
                "'max_speeed' from command line (-p) (did you mean 'max_speed'?)",
            }));
  // Declaring the name makes it used.
  p.declare("completely_unrelated", 0);
  EXPECT_EQ(p.unusedOverrides().size(), 4u);
}

// ---------------------------------------------------------------------------------------------
// Malformed input

TEST(ParametersTest, MalformedYamlReportsSourceLineAndColumn) {
  Parameters p("planner");
  const std::string message = errorOf([&] {
    p.loadYaml("planner:\n  rate: 1.0\n  list: [1, 2\n  other: 3\n", "/path/params.yaml");
  });
  EXPECT_TEXT(message, MatchesRegex("/path/params\\.yaml:[0-9]+:[0-9]+: malformed YAML: .+"));
  EXPECT_TEXT(message, Not(HasSubstr("yaml-cpp: error")));  // bare message, location once

  const std::string bad_indent =
      errorOf([&] { p.loadYaml("planner:\n  rate: 1.0\n bad: 2\n", "/path/params.yaml"); });
  EXPECT_TEXT(bad_indent, StartsWith("/path/params.yaml:3:"));
  EXPECT_TEXT(bad_indent, HasSubstr("malformed YAML"));

  const std::string path = writeTempFile("malformed.yaml", "planner:\n  a: 1\n  b: [\n");
  EXPECT_TEXT(errorOf([&] { p.loadFile(path); }), StartsWith(path + ":"));
  // A failed load keeps nothing.
  EXPECT_DOUBLE_EQ(p.declare("rate", 9.0), 9.0);
}

TEST(ParametersTest, StructuralErrorsNameTheLocation) {
  Parameters p("planner");
  EXPECT_EQ(errorOf([&] { p.loadYaml("- a\n- b\n", "f.yaml"); }),
            "f.yaml:1:1: expected a map of node names at the top level, got a list");
  EXPECT_EQ(errorOf([&] { p.loadYaml("planner: 5\n", "f.yaml"); }),
            "f.yaml:1:10: section 'planner' must be a map of parameters, got a scalar");
  EXPECT_EQ(errorOf([&] { p.loadYaml("/**: [1]\n", "f.yaml"); }),
            "f.yaml:1:6: section '/**' must be a map of parameters, got a list");
  // Other nodes' sections are not checked: they belong to other components.
  p.loadYaml("mapper: 5\n", "f.yaml");
}

TEST(ParametersTest, ParameterSetTwiceInOneFileIsAnError) {
  Parameters p("planner");
  EXPECT_EQ(errorOf([&] { p.loadYaml("planner:\n  a: 1\n  b: 2\n  a: 3\n", "f.yaml"); }),
            "f.yaml:4:3: parameter 'a' is set twice for the same node (first at line 2)");
  EXPECT_EQ(errorOf([&] { p.loadYaml("planner:\n  x: {y: 1}\n  x.y: 2\n", "f.yaml"); }),
            "f.yaml:3:3: parameter 'x.y' is set twice for the same node (first at line 2)");
  // The same name in the node section and the wildcard section is precedence, not a duplicate.
  p.loadYaml("planner: {a: 1}\n/**: {a: 2}\n", "f.yaml");
  EXPECT_EQ(p.declare<int>("a", 0), 1);
}

TEST(ParametersTest, AliasesSetParametersButNeverIntoACycle) {
  Parameters p("planner");
  // An alias inside the map it refers to made the file's flattening recurse until the stack
  // overflowed; one inside a list, the message about a bad element.
  EXPECT_TEXT(errorOf([&] { p.loadYaml("planner: &a {rate: 1, again: *a}\n", "f.yaml"); }),
              StartsWith("f.yaml:1:"));
  EXPECT_TEXT(errorOf([&] { p.loadYaml("planner:\n  ids: &a [1, *a]\n", "f.yaml"); }),
              HasSubstr("f.yaml:2:"));
  EXPECT_TEXT(errorOf([&] { p.loadYaml("planner:\n  ids: &a [1, *a]\n", "f.yaml"); }),
              HasSubstr("malformed YAML: an alias inside the node it refers to"));
  EXPECT_TEXT(errorOf([&] { p.setOverride("ids:=&a [1, *a]"); }), HasSubstr("an alias inside"));
  // Aliases of a map with many parameters: each alias sets them all under its own name (and a
  // repeated name is still found, quickly, among thousands; config::kMaxAliasedNodes bounds
  // how many).
  std::string many = "planner:\n  base: &base {";
  for (int i = 0; i < 100; ++i)
    many += (i ? ", k" : "k") + std::to_string(i) + ": " + std::to_string(i);
  many += "}\n";
  for (int i = 0; i < 40; ++i) many += "  copy" + std::to_string(i) + ": *base\n";
  p.loadYaml(many, "many.yaml");
  EXPECT_EQ(p.declare<int>("copy39.k99", 0), 99);
  EXPECT_EQ(p.unusedOverrides().size(), 4099u);
  // (first set where the aliased map writes it)
  EXPECT_EQ(errorOf([&] { p.loadYaml(many + "  copy0: {k5: 1}\n", "many.yaml"); }),
            "many.yaml:43:11: parameter 'copy0.k5' is set twice for the same node (first at "
            "line 2)");
}

TEST(ParametersTest, MalformedOverridesThrow) {
  Parameters p("planner");
  EXPECT_EQ(errorOf([&] { p.setOverride("rate=5"); }),
            "command line (-p): expected 'name:=value', got 'rate=5'");
  EXPECT_EQ(errorOf([&] { p.setOverride(":=5"); }),
            "command line (-p): expected 'name:=value', got ':=5'");
  EXPECT_TEXT(errorOf([&] { p.setOverride("ids:=[1, 2"); }),
              StartsWith("command line (-p): malformed value for parameter 'ids': "));
  EXPECT_EQ(errorOf([&] { p.setOverride("x:={a: 1}"); }),
            "command line (-p): value for parameter 'x' must be a scalar or a list, got a map");
  // Quoting on the command line keeps a string: "5" is not an integer.
  p.setOverride("count:=\"5\"");
  EXPECT_TEXT(errorOf([&] { p.declare<int>("count", 1); }),
              HasSubstr("got \"5\" (a quoted string)"));
  // A URL is a plain scalar, not a map.
  p.setOverride("url:=http://host:8080/x");
  EXPECT_EQ(p.declare("url", ""), "http://host:8080/x");
}

// ---------------------------------------------------------------------------------------------
// describe()

TEST(ParametersTest, DescribeIsYamlWithEveryField) {
  Parameters p("planner");
  p.loadYaml("planner: {planner: {range: 2.5}}\n", "params.yaml");
  ParameterDescriptor range = rangeDescriptor(0.1, 50, "m");
  range.description = "maximum planning range";
  p.declare("planner.range", 1.0, range);
  ParameterDescriptor modes;
  modes.choices = {"fast", "slow"};
  modes.read_only = true;
  p.declare("mode", "fast", modes);
  p.declare<uint8_t>("retries", 3);
  p.declare("ids", std::vector<int64_t>{1, 2});
  p.declare("label", "true");  // a string that looks like a bool stays a string

  const YAML::Node doc = YAML::Load(p.describe());
  ASSERT_TRUE(doc.IsMap());
  ASSERT_EQ(doc.size(), 5u);
  // Declaration order is kept.
  auto it = doc.begin();
  EXPECT_EQ(it->first.as<std::string>(), "planner.range");
  const YAML::Node r = doc["planner.range"];
  EXPECT_EQ(r["type"].as<std::string>(), "double");
  EXPECT_DOUBLE_EQ(r["value"].as<double>(), 2.5);
  EXPECT_EQ(r["unit"].as<std::string>(), "m");
  EXPECT_DOUBLE_EQ(r["min"].as<double>(), 0.1);
  EXPECT_DOUBLE_EQ(r["max"].as<double>(), 50.0);
  EXPECT_EQ(r["description"].as<std::string>(), "maximum planning range");
  EXPECT_EQ(r["source"].as<std::string>(), "params.yaml");
  EXPECT_FALSE(r["read_only"]);
  const YAML::Node m = doc["mode"];
  EXPECT_EQ(m["type"].as<std::string>(), "string");
  EXPECT_EQ(m["value"].as<std::string>(), "fast");
  EXPECT_EQ(m["choices"].as<std::vector<std::string>>(),
            (std::vector<std::string>{"fast", "slow"}));
  EXPECT_TRUE(m["read_only"].as<bool>());
  EXPECT_EQ(m["source"].as<std::string>(), "default");
  const YAML::Node n = doc["retries"];
  EXPECT_EQ(n["type"].as<std::string>(), "integer");
  EXPECT_EQ(n["value"].as<int>(), 3);
  EXPECT_EQ(n["min"].as<int>(), 0);
  EXPECT_EQ(n["max"].as<int>(), 255);
  EXPECT_EQ(doc["ids"]["value"].as<std::vector<int>>(), (std::vector<int>{1, 2}));
  EXPECT_EQ(doc["ids"]["type"].as<std::string>(), "integer_array");
  EXPECT_EQ(doc["label"]["value"].Tag(), "!");  // emitted quoted
  EXPECT_EQ(doc["label"]["value"].as<std::string>(), "true");
}

TEST(ParametersTest, DescribeOfNothingIsAnEmptyMap) {
  Parameters p("planner");
  const YAML::Node doc = YAML::Load(p.describe());
  EXPECT_TRUE(doc.IsMap());
  EXPECT_EQ(doc.size(), 0u);
}

TEST(ParametersTest, ValueToStringFormatsForMessages) {
  EXPECT_EQ(toString(ParameterValue(2.5)), "2.5");
  EXPECT_EQ(toString(ParameterValue(0.1)), "0.1");
  EXPECT_EQ(toString(ParameterValue(true)), "true");
  EXPECT_EQ(toString(ParameterValue(int64_t{-3})), "-3");
  EXPECT_EQ(toString(ParameterValue(std::string())), "\"\"");
  EXPECT_EQ(toString(ParameterValue(std::vector<std::string>{"a", "b"})), "[a, b]");
  EXPECT_EQ(toString(ParameterValue(std::vector<double>{})), "[]");
}

// ---------------------------------------------------------------------------------------------
// Thread safety

TEST(ParametersTest, ConcurrentGetAndSetSeeOnlyValidValues) {
  Parameters p("planner");
  p.declare("gain", 1.0, rangeDescriptor(0, 100));
  p.declare("ids", std::vector<int64_t>{0, 0});
  std::atomic<bool> stop{false};
  std::atomic<int> bad{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 4; ++t) {
    readers.emplace_back([&] {
      while (!stop) {
        const double gain = p.get<double>("gain");
        const auto ids = p.get<std::vector<int64_t>>("ids");
        if (gain < 0 || gain > 100 || ids.size() != 2 || ids[0] != ids[1]) ++bad;
        if (p.describe().empty()) ++bad;
      }
    });
  }
  std::vector<std::thread> writers;
  for (int t = 0; t < 2; ++t) {
    writers.emplace_back([&, t] {
      for (int i = 0; i < 500; ++i) {
        EXPECT_TRUE(p.set("gain", static_cast<double>(i % 100)).ok);
        EXPECT_TRUE(p.set("ids", std::vector<int64_t>{i + t, i + t}).ok);
        EXPECT_FALSE(p.set("gain", 200.0).ok);
      }
    });
  }
  for (auto& w : writers) w.join();
  stop = true;
  for (auto& r : readers) r.join();
  EXPECT_EQ(bad, 0);
}

}  // namespace
}  // namespace auv::interfaces
