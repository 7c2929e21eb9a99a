// Tests of the launch library: launch file parsing and validation, command building, the
// Supervisor (restart policies, required processes, shutdown escalation, environment, output
// prefixing, reaping) and the `auv launch` entry point. Children are small shell commands.

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "launch_description.h"
#include "launch_main.h"
#include "process_command.h"
#include "supervisor.h"

namespace auv::bringup {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// A scratch folder, removed with its content at the end of the test.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (fs::temp_directory_path() / "launch_test-XXXXXX").string();
    EXPECT_NE(mkdtemp(pattern.data()), nullptr);
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code error;
    fs::remove_all(path_, error);
  }
  const fs::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

  std::string write(const std::string& name, const std::string& content) const {
    fs::create_directories((path_ / name).parent_path());
    std::ofstream(path_ / name) << content;
    return file(name);
  }

 private:
  fs::path path_;
};

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream content;
  content << in.rdbuf();
  return content.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) result.push_back(line);
  return result;
}

// Parses `yaml` expecting a LaunchFileError and returns it.
LaunchFileError parseError(const std::string& yaml, const std::string& base_dir = "/") {
  try {
    parseLaunchYaml(yaml, "demo.yaml", base_dir);
  } catch (const LaunchFileError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return LaunchFileError("", "", "");
}

// ---------------------------------------------------------------------------------------------
// Parsing.

constexpr const char* kFullExample = R"(
environment: {AUV_DOMAIN_ID: "7"}
shutdown_timeout: 2.5
processes:
  - name: talker
    component: demo_talker
    vendor: fastdds
    parameters: {rate_hz: 10.0, frame: "123"}
    params_file: params/talker.yaml
    environment: {FOO: bar}
    restart: on-failure
    max_restarts: 3
    restart_delay: 0.5
    required: false
  - name: vehicle
    components:
      - {component: demo_talker, name: talker2, parameters: {rate_hz: 2.0}}
      - {component: demo_listener, name: listener2}
  - name: probe
    command: [auv, topic, echo, /chatter, --once]
    vendor: cyclonedds
    required: true
)";

TEST(LaunchDescriptionTest, ParsesFullExample) {
  ScratchDir dir;
  dir.write("params/talker.yaml", "talker: {rate_hz: 5.0}\n");
  const std::string file = dir.write("demo.yaml", kFullExample);

  const LaunchDescription launch = parseLaunchFile(file);

  EXPECT_EQ(launch.source, file);
  EXPECT_EQ(launch.base_dir, dir.path().string());
  EXPECT_EQ(launch.environment.at("AUV_DOMAIN_ID"), "7");
  EXPECT_DOUBLE_EQ(launch.shutdown_timeout, 2.5);
  ASSERT_EQ(launch.processes.size(), 3u);

  const ProcessDescription& talker = launch.processes[0];
  EXPECT_EQ(talker.name, "talker");
  EXPECT_EQ(talker.kind, ProcessKind::COMPONENT);
  ASSERT_EQ(talker.components.size(), 1u);
  EXPECT_EQ(talker.components[0].component, "demo_talker");
  EXPECT_EQ(talker.components[0].node_name, "talker");
  EXPECT_DOUBLE_EQ(talker.components[0].parameters["rate_hz"].as<double>(), 10.0);
  EXPECT_EQ(talker.vendor, DdsVendor::FASTDDS);
  EXPECT_EQ(talker.params_file, dir.file("params/talker.yaml"));
  EXPECT_EQ(talker.environment.at("FOO"), "bar");
  EXPECT_EQ(talker.restart, RestartPolicy::ON_FAILURE);
  EXPECT_EQ(talker.max_restarts, 3);
  EXPECT_DOUBLE_EQ(talker.restart_delay, 0.5);
  EXPECT_FALSE(talker.required);

  const ProcessDescription& vehicle = launch.processes[1];
  EXPECT_EQ(vehicle.kind, ProcessKind::COMPOSITION);
  ASSERT_EQ(vehicle.components.size(), 2u);
  EXPECT_EQ(vehicle.components[0].component, "demo_talker");
  EXPECT_EQ(vehicle.components[0].node_name, "talker2");
  EXPECT_EQ(vehicle.components[1].node_name, "listener2");
  EXPECT_FALSE(vehicle.components[1].parameters.IsMap());
  EXPECT_EQ(vehicle.restart, RestartPolicy::NEVER);  // defaults
  EXPECT_FALSE(vehicle.max_restarts.has_value());
  EXPECT_DOUBLE_EQ(vehicle.restart_delay, 1.0);
  EXPECT_EQ(vehicle.vendor, DdsVendor::DEFAULT);

  const ProcessDescription& probe = launch.processes[2];
  EXPECT_EQ(probe.kind, ProcessKind::COMMAND);
  EXPECT_THAT(probe.command, ElementsAre("auv", "topic", "echo", "/chatter", "--once"));
  EXPECT_TRUE(probe.required);
  EXPECT_EQ(probe.vendor, DdsVendor::CYCLONEDDS);
}

TEST(LaunchDescriptionTest, ArgumentsAreSubstitutedWithDefaultsAndCommandLineValues) {
  constexpr const char* kYaml = R"(
arguments:
  world: {default: canyon, description: world name}
  seed: "1"
processes:
  - name: sim
    component: simulator
    parameters: {world: $(arg world), seed: $(arg seed), run_dir: runs/$(arg world)-$(arg seed)}
)";
  const LaunchDescription defaults = parseLaunchYaml(kYaml, "sim.yaml", "/");
  const YAML::Node p = defaults.processes[0].components[0].parameters;
  EXPECT_EQ(p["world"].as<std::string>(), "canyon");
  EXPECT_EQ(p["seed"].as<int>(), 1);  // still a number for the parameter parser
  EXPECT_EQ(p["run_dir"].as<std::string>(), "runs/canyon-1");
  ASSERT_EQ(defaults.arguments.size(), 2u);
  EXPECT_EQ(defaults.arguments[0].description, "world name");

  const LaunchDescription given =
      parseLaunchYaml(kYaml, "sim.yaml", "/", {{"world", "breakwater"}});
  EXPECT_EQ(given.processes[0].components[0].parameters["run_dir"].as<std::string>(),
            "runs/breakwater-1");

  // An argument's value may use the arguments declared before it.
  constexpr const char* kChained = R"yaml(
arguments:
  world: canyon
  run_dir: {default: "runs/$(arg world)"}
processes:
  - {name: sim, component: simulator, parameters: {run_dir: $(arg run_dir)}}
)yaml";
  const LaunchDescription chained =
      parseLaunchYaml(kChained, "sim.yaml", "/", {{"world", "breakwater"}});
  EXPECT_EQ(chained.processes[0].components[0].parameters["run_dir"].as<std::string>(),
            "runs/breakwater");
  const LaunchDescription overridden =
      parseLaunchYaml(kChained, "sim.yaml", "/", {{"run_dir", "elsewhere"}});
  EXPECT_EQ(overridden.processes[0].components[0].parameters["run_dir"].as<std::string>(),
            "elsewhere");
}

TEST(LaunchDescriptionTest, EnabledLeavesProcessesOutAndRejectsNonBooleans) {
  constexpr const char* kYaml = R"(
arguments:
  auto_run: {default: "false"}
processes:
  - {name: sim, command: [sleep, "1"]}
  - {name: runner, enabled: $(arg auto_run), command: [echo, run], required: true}
)";
  const LaunchDescription off = parseLaunchYaml(kYaml, "v.yaml", "/");
  ASSERT_EQ(off.processes.size(), 1u);
  EXPECT_EQ(off.processes[0].name, "sim");
  const LaunchDescription on = parseLaunchYaml(kYaml, "v.yaml", "/", {{"auto_run", "true"}});
  ASSERT_EQ(on.processes.size(), 2u);
  EXPECT_EQ(on.processes[1].name, "runner");
  EXPECT_TRUE(on.processes[1].required);
  try {
    parseLaunchYaml(kYaml, "v.yaml", "/", {{"auto_run", "maybe"}});
    ADD_FAILURE() << "accepted enabled: maybe";
  } catch (const LaunchFileError& e) {
    EXPECT_EQ(e.field(), "processes[1].enabled");
  }
}

TEST(LaunchDescriptionTest, ArgumentErrorsNameTheArgument) {
  constexpr const char* kYaml =
      "arguments: {world: {default: canyon}, rate: {description: required}}\n"
      "processes:\n  - {name: a, command: [echo, $(arg world), $(arg rate)]}\n";
  try {
    parseLaunchYaml(kYaml, "sim.yaml", "/", {{"wrold", "x"}, {"rate", "1"}});
    ADD_FAILURE() << "accepted an undeclared argument";
  } catch (const LaunchFileError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'world'"), std::string::npos) << e.what();
  }
  try {
    parseLaunchYaml(kYaml, "sim.yaml", "/");
    ADD_FAILURE() << "accepted a missing required argument";
  } catch (const LaunchFileError& e) {
    EXPECT_NE(std::string(e.what()).find("arguments.rate"), std::string::npos) << e.what();
  }
  const LaunchFileError undeclared =
      parseError("processes:\n  - {name: a, command: [echo, $(arg nope)]}\n");
  EXPECT_NE(std::string(undeclared.what()).find("$(arg nope)"), std::string::npos);
  EXPECT_EQ(undeclared.field(), "processes[0].command[1]");
}

TEST(LaunchDescriptionTest, EnvSubstitutionTakesTheEnvironmentOrItsDefault) {
  constexpr const char* kYaml = R"yaml(
arguments:
  domain: {default: "$(env AUV_LAUNCH_TEST_DOMAIN 0)"}
processes:
  - {name: a, command: [echo, $(arg domain), "$(env AUV_LAUNCH_TEST_WORD fallback words)"]}
)yaml";
  auto command = [&](const std::map<std::string, std::string>& arguments = {}) {
    return parseLaunchYaml(kYaml, "env.yaml", "/", arguments).processes[0].command;
  };
  ::unsetenv("AUV_LAUNCH_TEST_DOMAIN");
  ::unsetenv("AUV_LAUNCH_TEST_WORD");
  EXPECT_THAT(command(), ElementsAre("echo", "0", "fallback words"));
  ::setenv("AUV_LAUNCH_TEST_DOMAIN", "17", 1);
  ::setenv("AUV_LAUNCH_TEST_WORD", "set", 1);
  EXPECT_THAT(command(), ElementsAre("echo", "17", "set"));
  EXPECT_THAT(command({{"domain", "5"}}), ElementsAre("echo", "5", "set"));  // name:= wins
  ::setenv("AUV_LAUNCH_TEST_DOMAIN", "", 1);  // exported but empty: as if unset
  EXPECT_THAT(command(), ElementsAre("echo", "0", "set"));
  ::unsetenv("AUV_LAUNCH_TEST_DOMAIN");
  ::unsetenv("AUV_LAUNCH_TEST_WORD");

  const LaunchFileError unset =
      parseError("processes:\n  - {name: a, command: [echo, \"$(env AUV_LAUNCH_TEST_NOPE)\"]}\n");
  EXPECT_EQ(unset.field(), "processes[0].command[1]");
  EXPECT_THAT(std::string(unset.what()), HasSubstr("AUV_LAUNCH_TEST_NOPE"));
  const LaunchFileError arg_default = parseError(
      "arguments: {x: \"1\"}\nprocesses:\n  - {name: a, command: [echo, \"$(arg x 2)\"]}\n");
  EXPECT_THAT(std::string(arg_default.what()), HasSubstr("takes no default"));
}

TEST(LaunchDescriptionTest, SubstitutionsInLongStringsAndSpacedDefaults) {
  // The substitutions were found by std::regex, which recursed once per character: a 64 kB
  // string (a long shell command) overflowed the stack.
  const std::string words(65536, 'w');
  const LaunchDescription launch = parseLaunchYaml(
      "arguments: {x: \"1\"}\nprocesses:\n  - {name: a, command: [echo, \"" + words +
          " $(arg x) $(env AUV_LAUNCH_TEST_NOPE  two  words  )" + words + "\"]}\n",
      "long.yaml", "/");
  EXPECT_EQ(launch.processes[0].command[1], words + " 1 two  words" + words);
  const LaunchFileError malformed =
      parseError("processes:\n  - {name: a, command: [echo, \"$(arg a " + words + "\"]}\n");
  EXPECT_EQ(malformed.field(), "processes[0].command[1]");
  EXPECT_THAT(std::string(malformed.what()), HasSubstr("malformed substitution"));
  // Not substitutions, left for that error: no space before the name, a parenthesis in the
  // default, an unknown kind; the next "$(" is still tried.
  for (const std::string text : {"$(argx)", "$(env X a(b))", "$(var x)", "$($(arg"}) {
    SCOPED_TRACE(text);
    EXPECT_THAT(
        std::string(
            parseError("processes:\n  - {name: a, command: [echo, \"" + text + "\"]}\n").what()),
        HasSubstr("malformed substitution"));
  }
  EXPECT_EQ(parseLaunchYaml("arguments: {x: \"1\"}\nprocesses:\n  - {name: a, command: [echo, "
                            "\"$(arg\tx\t)$(env AUV_LAUNCH_TEST_NOPE d)\"]}\n",
                            "tabs.yaml", "/")
                .processes[0]
                .command[1],
            "1d");
}

TEST(LaunchDescriptionTest, AnAliasInsideWhatItRefersToIsMalformedYaml) {
  // yaml-cpp makes such a node contain itself: the substitutions and the inline parameters'
  // checks walked it until the stack overflowed.
  for (const std::string yaml :
       {"x: &a [*a]\nprocesses:\n  - {name: a, command: [ls]}\n",
        "processes:\n  - {name: a, component: b, parameters: &p {x: *p}}\n"}) {
    SCOPED_TRACE(yaml);
    const LaunchFileError error = parseError(yaml);
    EXPECT_THAT(std::string(error.what()), HasSubstr("malformed YAML: an alias inside"));
    EXPECT_GT(error.line(), 0);
  }
}

TEST(LaunchDescriptionTest, MinimalFileGetsDefaults) {
  const LaunchDescription launch =
      parseLaunchYaml("processes:\n  - {name: a, command: [true]}\n", "min.yaml", "/");
  EXPECT_DOUBLE_EQ(launch.shutdown_timeout, 5.0);
  EXPECT_TRUE(launch.environment.empty());
  ASSERT_EQ(launch.processes.size(), 1u);
  EXPECT_EQ(launch.processes[0].restart, RestartPolicy::NEVER);
  EXPECT_FALSE(launch.processes[0].required);
}

TEST(LaunchDescriptionTest, ErrorMessageNamesFileAndFieldAsDocumented) {
  const LaunchFileError e = parseError(R"(processes:
  - {name: a, command: [true]}
  - name: b
    command: [true]
    restart: sometimes
)");
  EXPECT_THAT(e.what(), StartsWith("demo.yaml: processes[1].restart: expected one of [never, "
                                   "on-failure, always], got 'sometimes'"));
  EXPECT_EQ(e.file(), "demo.yaml");
  EXPECT_EQ(e.field(), "processes[1].restart");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 14);
  EXPECT_THAT(e.what(), HasSubstr("(line 5, column 14)"));
}

struct InvalidCase {
  const char* label;
  const char* yaml;
  const char* field;    // expected field path
  const char* problem;  // expected substring of the message
};

class InvalidLaunchFileTest : public ::testing::TestWithParam<InvalidCase> {};

TEST_P(InvalidLaunchFileTest, NamesFileAndField) {
  const InvalidCase& c = GetParam();
  const LaunchFileError e = parseError(c.yaml);
  EXPECT_EQ(e.file(), "demo.yaml");
  EXPECT_EQ(e.field(), c.field);
  EXPECT_THAT(e.what(), StartsWith(std::string("demo.yaml: ") + c.field + ": "));
  EXPECT_THAT(e.what(), HasSubstr(c.problem));
}

const InvalidCase kInvalidCases[] = {
    {"UnknownTopLevelKeyWithSuggestion", "proceses: []\n", "proceses",
     "unknown key; did you mean 'processes'?"},
    {"UnknownProcessKeyWithSuggestion", "processes:\n  - {name: a, command: [x], restat: always}\n",
     "processes[0].restat", "did you mean 'restart'?"},
    {"TransposedLettersSuggestion", "processes:\n  - {name: a, command: [x], restart_dealy: 1}\n",
     "processes[0].restart_dealy", "did you mean 'restart_delay'?"},
    {"AliasSuggestion", "processes:\n  - {name: a, command: [x], env: {A: b}}\n",
     "processes[0].env", "did you mean 'environment'?"},
    {"UnknownKeyWithoutSuggestion", "processes:\n  - {name: a, command: [x], zzzzzz: 1}\n",
     "processes[0].zzzzzz", "unknown key; expected one of [name, component,"},
    {"UnknownComponentEntryKey",
     "processes:\n  - name: v\n    components:\n      - {component: c, nmae: n}\n",
     "processes[0].components[0].nmae", "did you mean 'name'?"},
    {"DuplicateKey", "processes:\n  - {name: a, command: [x], name: b}\n", "processes[0].name",
     "duplicate key"},
    {"MissingProcesses", "environment: {A: b}\n", "processes", "missing required key"},
    {"ProcessesNotAList", "processes: {name: a}\n", "processes",
     "expected a list of processes, got a mapping"},
    {"EmptyProcesses", "processes: []\n", "processes", "at least one process"},
    {"ProcessNotAMapping", "processes:\n  - just_a_string\n", "processes[0]",
     "expected a mapping describing a process, got 'just_a_string'"},
    {"MissingName", "processes:\n  - {command: [x]}\n", "processes[0].name",
     "missing required key"},
    {"InvalidName", "processes:\n  - {name: 'my proc', command: [x]}\n", "processes[0].name",
     "invalid process name 'my proc'"},
    {"DuplicateName", "processes:\n  - {name: a, command: [x]}\n  - {name: a, command: [y]}\n",
     "processes[1].name", "duplicate process name 'a' (first used by processes[0])"},
    {"NoKind", "processes:\n  - {name: a}\n", "processes[0]",
     "expected exactly one of 'component', 'components' or 'command', got none"},
    {"TwoKinds", "processes:\n  - {name: a, component: c, command: [x]}\n", "processes[0].command",
     "got both 'component' and 'command'"},
    {"CommandAsString", "processes:\n  - {name: a, command: 'echo hi'}\n", "processes[0].command",
     "expected a list of arguments"},
    {"EmptyCommand", "processes:\n  - {name: a, command: []}\n", "processes[0].command",
     "expected at least the program name"},
    {"CommandArgumentNotString", "processes:\n  - {name: a, command: [x, {y: 1}]}\n",
     "processes[0].command[1]", "expected a string argument, got a mapping"},
    {"BadVendorWithSuggestion", "processes:\n  - {name: a, command: [x], vendor: fastdd}\n",
     "processes[0].vendor",
     "expected one of [cyclonedds, fastdds], got 'fastdd'; did you mean 'fastdds'?"},
    {"RestartUnderscoreSuggestion",
     "processes:\n  - {name: a, command: [x], restart: on_failure}\n", "processes[0].restart",
     "did you mean 'on-failure'?"},
    {"NegativeMaxRestarts", "processes:\n  - {name: a, command: [x], max_restarts: -1}\n",
     "processes[0].max_restarts", "expected a non-negative integer, got '-1'"},
    {"FractionalMaxRestarts", "processes:\n  - {name: a, command: [x], max_restarts: 1.5}\n",
     "processes[0].max_restarts", "expected a non-negative integer, got '1.5'"},
    {"NegativeRestartDelay", "processes:\n  - {name: a, command: [x], restart_delay: -2}\n",
     "processes[0].restart_delay", "expected a duration in seconds >= 0, got '-2'"},
    {"ShutdownTimeoutNotANumber",
     "shutdown_timeout: soon\nprocesses:\n  - {name: a, command: [x]}\n", "shutdown_timeout",
     "expected a duration in seconds >= 0, got 'soon'"},
    {"InfiniteShutdownTimeout", "shutdown_timeout: .inf\nprocesses:\n  - {name: a, command: [x]}\n",
     "shutdown_timeout", "got '.inf'"},
    {"RequiredNotBool", "processes:\n  - {name: a, command: [x], required: maybe}\n",
     "processes[0].required", "expected true or false, got 'maybe'"},
    {"RequiredYesIsNotABool", "processes:\n  - {name: a, command: [x], required: yes}\n",
     "processes[0].required", "expected true or false, got 'yes'"},
    {"EnvironmentNotAMapping", "environment: [A]\nprocesses:\n  - {name: a, command: [x]}\n",
     "environment", "expected a mapping of NAME: value, got a list"},
    {"EnvironmentValueNotScalar",
     "processes:\n  - {name: a, command: [x], environment: {FOO: [1, 2]}}\n",
     "processes[0].environment.FOO", "expected a string value, got a list"},
    {"EnvironmentBadName", "environment: {1FOO: x}\nprocesses:\n  - {name: a, command: [x]}\n",
     "environment.1FOO", "invalid environment variable name"},
    {"ParametersOnCommand", "processes:\n  - {name: a, command: [x], parameters: {p: 1}}\n",
     "processes[0].parameters", "not allowed on a 'command' process"},
    {"ParametersOnComposition",
     "processes:\n  - name: v\n    parameters: {p: 1}\n    components: [{component: c}]\n",
     "processes[0].parameters", "give parameters per entry"},
    {"ParametersNotAMapping", "processes:\n  - {name: a, component: c, parameters: [1]}\n",
     "processes[0].parameters", "expected a mapping of parameter: value, got a list"},
    {"ParameterWithoutValue",
     "processes:\n  - name: a\n    component: c\n    parameters:\n      rate:\n",
     "processes[0].parameters.rate", "missing value"},
    {"EmptyComposition", "processes:\n  - {name: v, components: []}\n", "processes[0].components",
     "expected at least one component"},
    {"CompositionEntryWithoutComponent", "processes:\n  - {name: v, components: [{name: n}]}\n",
     "processes[0].components[0].component", "missing required key"},
    {"DuplicateNodeNameInComposition",
     "processes:\n  - name: v\n    components: [{component: c}, {component: c}]\n",
     "processes[0].components[1].name", "duplicate node name 'c'"},
    {"InvalidComponentName", "processes:\n  - {name: a, component: 'demo:talker'}\n",
     "processes[0].component", "invalid component name 'demo:talker'"},
    {"MissingParamsFile", "processes:\n  - {name: a, component: c, params_file: nope.yaml}\n",
     "processes[0].params_file", "file not found: /nope.yaml"},
};

INSTANTIATE_TEST_SUITE_P(Cases, InvalidLaunchFileTest, ::testing::ValuesIn(kInvalidCases),
                         [](const auto& info) { return std::string(info.param.label); });

TEST(LaunchDescriptionTest, MalformedYamlReportsLineAndColumn) {
  const LaunchFileError e = parseError("processes:\n  - name: a\n    command: [x, y\n");
  EXPECT_EQ(e.file(), "demo.yaml");
  EXPECT_GT(e.line(), 0);
  EXPECT_GT(e.column(), 0);
  EXPECT_THAT(e.what(), StartsWith("demo.yaml:" + std::to_string(e.line()) + ":" +
                                   std::to_string(e.column()) + ": malformed YAML: "));

  const LaunchFileError indent = parseError("processes:\n  - name: a\n   command: [x]\n");
  EXPECT_EQ(indent.line(), 3);
  EXPECT_THAT(indent.what(), StartsWith("demo.yaml:3:"));
}

TEST(LaunchDescriptionTest, UnreadableOrEmptyFileIsNamed) {
  ScratchDir dir;
  try {
    parseLaunchFile(dir.file("missing.yaml"));
    FAIL() << "no error";
  } catch (const LaunchFileError& e) {
    EXPECT_EQ(e.file(), dir.file("missing.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("cannot open"));
  }
  try {
    parseLaunchFile(dir.write("empty.yaml", "# nothing\n"));
    FAIL() << "no error";
  } catch (const LaunchFileError& e) {
    EXPECT_THAT(e.what(), StartsWith(dir.file("empty.yaml") + ": empty launch file"));
  }
}

TEST(LaunchDescriptionTest, CheckRejectsBadProgrammaticDescription) {
  LaunchDescription launch;
  launch.source = "code";
  ProcessDescription process;
  process.name = "a";
  process.command = {"true"};
  launch.processes = {process, process};
  try {
    launch.check();
    FAIL() << "duplicate accepted";
  } catch (const LaunchFileError& e) {
    EXPECT_EQ(e.field(), "processes[1].name");
  }
  launch.processes.resize(1);
  launch.processes[0].restart_delay = -1.0;
  EXPECT_THROW(launch.check(), LaunchFileError);
  launch.processes[0].restart_delay = 0.0;
  EXPECT_NO_THROW(launch.check());
}

// ---------------------------------------------------------------------------------------------
// Command building.

TEST(ProcessCommandTest, BuildsAuvRunCommandsAndEnvironment) {
  ScratchDir dir;
  dir.write("params/talker.yaml", "talker: {rate_hz: 5.0}\n");
  const LaunchDescription launch = parseLaunchFile(dir.write("demo.yaml", kFullExample));

  const ProcessCommand talker =
      buildProcessCommand(launch, launch.processes[0], "/opt/auv/bin/auv", "/tmp/p");
  EXPECT_THAT(talker.argv,
              ElementsAre("/opt/auv/bin/auv", "run", "demo_talker:talker", "--params",
                          dir.file("params/talker.yaml"), "--params", "/tmp/p/talker.params.yaml"));
  EXPECT_EQ(talker.inline_params_path, "/tmp/p/talker.params.yaml");
  EXPECT_EQ(talker.environment,
            (std::map<std::string, std::string>{
                {"AUV_DDS", "fastdds"}, {"AUV_DOMAIN_ID", "7"}, {"FOO", "bar"}}));

  // Inline parameters are keyed by node name; quoted strings stay strings.
  const YAML::Node params = YAML::Load(talker.inline_params_yaml);
  EXPECT_DOUBLE_EQ(params["talker"]["rate_hz"].as<double>(), 10.0);
  EXPECT_EQ(params["talker"]["frame"].Tag(), "!");  // quoted -> string, not the int 123

  const ProcessCommand vehicle =
      buildProcessCommand(launch, launch.processes[1], "/opt/auv/bin/auv", "/tmp/p");
  EXPECT_THAT(vehicle.argv,
              ElementsAre("/opt/auv/bin/auv", "run", "demo_talker:talker2",
                          "demo_listener:listener2", "--params", "/tmp/p/vehicle.params.yaml"));
  const YAML::Node vehicle_params = YAML::Load(vehicle.inline_params_yaml);
  EXPECT_TRUE(vehicle_params["talker2"]);
  EXPECT_FALSE(vehicle_params["listener2"]);  // no inline parameters for it

  const ProcessCommand probe =
      buildProcessCommand(launch, launch.processes[2], "/opt/auv/bin/auv", "/tmp/p");
  EXPECT_THAT(probe.argv, ElementsAre("/opt/auv/bin/auv", "topic", "echo", "/chatter", "--once"));
  EXPECT_TRUE(probe.inline_params_path.empty());
  EXPECT_EQ(probe.environment.at("AUV_DDS"), "cyclonedds");

  EXPECT_THROW(buildProcessCommand(launch, launch.processes[0], "", "/tmp/p"),
               std::invalid_argument);
}

TEST(ProcessCommandTest, VendorOverridesEnvironmentAndProcessOverridesLaunch) {
  const LaunchDescription launch = parseLaunchYaml(R"(
environment: {A: launch, B: launch}
processes:
  - name: p
    command: [env]
    vendor: cyclonedds
    environment: {B: process, AUV_DDS: fastdds}
)",
                                                   "t.yaml", "/");
  const ProcessCommand command = buildProcessCommand(launch, launch.processes[0], "", "");
  EXPECT_EQ(command.environment.at("A"), "launch");
  EXPECT_EQ(command.environment.at("B"), "process");
  EXPECT_EQ(command.environment.at("AUV_DDS"), "cyclonedds");

  const char* base[] = {"PATH=/bin", "A=parent", "KEEP=1", nullptr};
  EXPECT_THAT(mergeEnvironment(base, command.environment),
              ElementsAre("A=launch", "AUV_DDS=cyclonedds", "B=process", "KEEP=1", "PATH=/bin"));
}

TEST(ProcessCommandTest, ShellQuoteAndFindExecutable) {
  EXPECT_EQ(shellQuote("plain/path-1.yaml"), "plain/path-1.yaml");
  EXPECT_EQ(shellQuote("exit 3"), "'exit 3'");
  EXPECT_EQ(shellQuote("it's"), "'it'\\''s'");
  EXPECT_EQ(shellQuote(""), "''");
  EXPECT_EQ(findExecutable("sh", "/nonexistent:/bin:/usr/bin"), "/bin/sh");
  EXPECT_EQ(findExecutable("no-such-program-xyz", "/bin:/usr/bin"), "");
  EXPECT_EQ(findExecutable("./relative", "/bin"), "./relative");
}

// ---------------------------------------------------------------------------------------------
// Supervisor.

// Runs launch YAML with outputs captured in files of a scratch folder.
class SupervisorTest : public ::testing::Test {
 protected:
  struct Result {
    LaunchReport report;
    std::string out;  // children's stdout lines
    std::string err;  // children's stderr lines
    std::string log;  // supervisor lines
    double seconds = 0.0;
  };

  SupervisorOptions makeOptions() {
    SupervisorOptions options;
    options.auv_executable = fake_auv_;
    options.stdout_fd = openCapture("out.txt");
    options.stderr_fd = openCapture("err.txt");
    options.log_fd = openCapture("log.txt");
    options.temp_dir = dir_.file("tmp");
    fs::create_directories(options.temp_dir);
    return options;
  }

  // `{dir}` in the YAML is replaced with the scratch folder.
  LaunchDescription parse(std::string yaml) {
    for (size_t at; (at = yaml.find("{dir}")) != std::string::npos;) {
      yaml.replace(at, 5, dir_.path().string());
    }
    return parseLaunchYaml(yaml, "test.yaml", dir_.path().string());
  }

  Result runLaunch(const std::string& yaml) { return runSupervisor(parse(yaml), makeOptions()); }

  // `expose` (optional) receives the supervisor before run() blocks.
  Result runSupervisor(LaunchDescription launch, SupervisorOptions options,
                       std::atomic<Supervisor*>* expose = nullptr) {
    Supervisor supervisor(std::move(launch), options);
    if (expose != nullptr) *expose = &supervisor;
    const auto start = std::chrono::steady_clock::now();
    Result result;
    result.report = supervisor.run();
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (int fd : {options.stdout_fd, options.stderr_fd, options.log_fd}) close(fd);
    result.out = readFile(dir_.file("out.txt"));
    result.err = readFile(dir_.file("err.txt"));
    result.log = readFile(dir_.file("log.txt"));
    expectAllReaped(result.report);
    return result;
  }

  // Every pid the supervisor ran is gone and reaped; the test process has no child left.
  static void expectAllReaped(const LaunchReport& report) {
    for (const ProcessReport& process : report.processes) {
      for (pid_t pid : process.pids) {
        EXPECT_EQ(waitpid(pid, nullptr, WNOHANG), -1) << process.name << " pid " << pid;
        EXPECT_EQ(kill(pid, 0), -1) << process.name << " pid " << pid << " still exists";
        EXPECT_EQ(errno, ESRCH);
      }
    }
    EXPECT_EQ(waitpid(-1, nullptr, WNOHANG), -1) << "a child of the test process is left";
    EXPECT_EQ(errno, ECHILD);
  }

  int openCapture(const std::string& name) {
    const int fd = open(dir_.file(name).c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    EXPECT_GE(fd, 0);
    return fd;
  }

  void SetUp() override {
    // Stand-in for the auv executable: prints its argv, AUV_DDS and the params files it gets.
    fake_auv_ = dir_.write("bin/auv", R"(#!/bin/sh
echo "argv: $*"
echo "dds: ${AUV_DDS:-unset}"
while [ $# -gt 0 ]; do
  if [ "$1" = "--params" ]; then shift; echo "params $1:"; cat "$1"; fi
  shift
done
)");
    chmod(fake_auv_.c_str(), 0755);
  }

  ScratchDir dir_;
  std::string fake_auv_;
};

TEST_F(SupervisorTest, AllProcessesExitZero) {
  const Result r = runLaunch(R"(
processes:
  - {name: a, command: [sh, -c, "exit 0"]}
  - {name: b, command: ["true"]}
)");
  EXPECT_EQ(r.report.exit_code, 0);
  EXPECT_EQ(r.report.end, LaunchEnd::ALL_EXITED);
  ASSERT_EQ(r.report.processes.size(), 2u);
  for (const ProcessReport& p : r.report.processes) {
    EXPECT_EQ(p.outcome, ProcessOutcome::EXITED) << p.name;
    EXPECT_EQ(p.exit_code, 0);
    EXPECT_EQ(p.restarts, 0);
    EXPECT_EQ(p.pids.size(), 1u);
    EXPECT_FALSE(p.stopped);
  }
  // One summary line per process.
  EXPECT_THAT(r.log, HasSubstr("[launch] a  exited with code 0, restarts: 0"));
  EXPECT_THAT(r.log, HasSubstr("[launch] b  exited with code 0, restarts: 0"));
  EXPECT_THAT(r.log, HasSubstr("[launch] exit code 0"));
}

TEST_F(SupervisorTest, NeverRestartReportsExitCode) {
  const Result r = runLaunch("processes:\n  - {name: a, command: [sh, -c, 'exit 3']}\n");
  EXPECT_EQ(r.report.exit_code, 3);
  const ProcessReport& a = r.report.processes[0];
  EXPECT_EQ(a.outcome, ProcessOutcome::EXITED);
  EXPECT_EQ(a.exit_code, 3);
  EXPECT_EQ(a.restarts, 0);
  EXPECT_FALSE(a.succeeded());
  EXPECT_THAT(r.log, HasSubstr("a  exited with code 3, restarts: 0"));
}

TEST_F(SupervisorTest, OnFailureRestartsUpToMaxRestarts) {
  const Result r = runLaunch(R"(
processes:
  - name: a
    command: [sh, -c, "echo run >> {dir}/runs; exit 3"]
    restart: on-failure
    max_restarts: 2
    restart_delay: 0
)");
  const ProcessReport& a = r.report.processes[0];
  EXPECT_EQ(a.restarts, 2);
  EXPECT_EQ(a.pids.size(), 3u);
  EXPECT_EQ(lines(readFile(dir_.file("runs"))).size(), 3u);
  EXPECT_EQ(a.exit_code, 3);
  EXPECT_EQ(r.report.exit_code, 3);
  EXPECT_THAT(r.log, HasSubstr("restart 2 of 2"));
  EXPECT_THAT(r.log, HasSubstr("max_restarts reached"));
  EXPECT_THAT(r.log, HasSubstr("a  exited with code 3, restarts: 2"));
}

// A restarted process learns it belongs to the same launch (what it may resume); another
// launch gets another id, and an exported AUV_LAUNCH_ID (resuming after a reboot) is kept.
TEST_F(SupervisorTest, ProcessesShareOneLaunchIdAcrossRestarts) {
  const std::string launch = R"(
processes:
  - name: a
    command: [sh, -c, "echo $AUV_LAUNCH_ID >> {dir}/ids; exit 3"]
    restart: on-failure
    max_restarts: 1
    restart_delay: 0
  - name: b
    command: [sh, -c, "echo $AUV_LAUNCH_ID >> {dir}/ids"]
)";
  ::unsetenv("AUV_LAUNCH_ID");
  runLaunch(launch);
  const std::vector<std::string> first = lines(readFile(dir_.file("ids")));
  ASSERT_EQ(first.size(), 3u);
  EXPECT_EQ(first[0].size(), 16u) << first[0];
  EXPECT_EQ(first[1], first[0]);
  EXPECT_EQ(first[2], first[0]);
  runLaunch(launch);
  const std::vector<std::string> both = lines(readFile(dir_.file("ids")));
  ASSERT_EQ(both.size(), 6u);
  EXPECT_NE(both[3], first[0]) << "a new launch is not the old one";
  ::setenv("AUV_LAUNCH_ID", "resumed", 1);
  runLaunch(launch);
  ::unsetenv("AUV_LAUNCH_ID");
  const std::vector<std::string> all = lines(readFile(dir_.file("ids")));
  ASSERT_EQ(all.size(), 9u);
  EXPECT_EQ(all[6], "resumed");
}

TEST_F(SupervisorTest, OnFailureStopsRestartingAfterSuccess) {
  const Result r = runLaunch(R"(
processes:
  - name: a
    command: [sh, -c, "if [ -f {dir}/flag ]; then exit 0; fi; touch {dir}/flag; exit 1"]
    restart: on-failure
    restart_delay: 0
  - name: b
    command: [sh, -c, "exit 0"]
    restart: on-failure
    restart_delay: 0
)");
  EXPECT_EQ(r.report.processes[0].restarts, 1);
  EXPECT_EQ(r.report.processes[0].exit_code, 0);
  EXPECT_EQ(r.report.processes[1].restarts, 0);  // success is not a failure
  EXPECT_EQ(r.report.exit_code, 0);              // the final run counts
}

TEST_F(SupervisorTest, AlwaysRestartsAfterSuccessWithDelay) {
  const Result r = runLaunch(R"(
processes:
  - {name: a, command: ["true"], restart: always, max_restarts: 2, restart_delay: 0.2}
)");
  const ProcessReport& a = r.report.processes[0];
  EXPECT_EQ(a.restarts, 2);
  EXPECT_EQ(a.pids.size(), 3u);
  EXPECT_EQ(r.report.exit_code, 0);
  EXPECT_GE(r.seconds, 0.4);  // two restart delays passed (a lower bound, not a deadline)
  EXPECT_THAT(r.log, HasSubstr("restarting in 0.2 s (restart 1 of 2)"));
}

TEST_F(SupervisorTest, ProgramNotFoundFailsWithoutRestart) {
  const Result r =
      runLaunch("processes:\n  - {name: a, command: [no-such-program-xyz], restart: always}\n");
  const ProcessReport& a = r.report.processes[0];
  EXPECT_EQ(a.outcome, ProcessOutcome::START_FAILED);
  EXPECT_THAT(a.start_error, HasSubstr("not found"));
  EXPECT_EQ(a.restarts, 0);
  EXPECT_TRUE(a.pids.empty());
  EXPECT_EQ(r.report.exit_code, 127);
}

TEST_F(SupervisorTest, RequiredProcessEndsLaunch) {
  const Result r = runLaunch(R"(
shutdown_timeout: 2
processes:
  - {name: server, command: [sleep, "10"]}
  - {name: probe, command: [sh, -c, "sleep 0.1; exit 0"], required: true}
)");
  EXPECT_EQ(r.report.end, LaunchEnd::REQUIRED_EXITED);
  EXPECT_EQ(r.report.exit_code, 0);
  const ProcessReport* server = r.report.find("server");
  ASSERT_NE(server, nullptr);
  EXPECT_TRUE(server->stopped);
  EXPECT_EQ(server->outcome, ProcessOutcome::SIGNALED);
  EXPECT_EQ(server->signal, SIGINT);  // it obeyed the first, polite signal
  EXPECT_EQ(server->strongest_stop_signal, SIGINT);
  EXPECT_FALSE(r.report.find("probe")->stopped);
  EXPECT_THAT(r.log, HasSubstr("required process probe ended; shutting down"));
}

TEST_F(SupervisorTest, RequiredFailureGivesExitCodeAndOthersDoNotCount) {
  const Result failing = runLaunch(R"(
processes:
  - {name: server, command: [sleep, "10"]}
  - {name: probe, command: [sh, -c, "exit 5"], required: true}
)");
  EXPECT_EQ(failing.report.exit_code, 5);

  const Result passing = runLaunch(R"(
processes:
  - {name: flaky, command: [sh, -c, "exit 9"]}
  - {name: probe, command: [sh, -c, "sleep 0.2; exit 0"], required: true}
)");
  EXPECT_EQ(passing.report.find("flaky")->exit_code, 9);
  EXPECT_EQ(passing.report.exit_code, 0);  // only required processes count
}

TEST_F(SupervisorTest, RequiredProcessUsesItsRestartsBeforeEndingLaunch) {
  const Result r = runLaunch(R"(
processes:
  - {name: server, command: [sleep, "10"]}
  - name: probe
    command: [sh, -c, "exit 4"]
    required: true
    restart: on-failure
    max_restarts: 1
    restart_delay: 0
)");
  EXPECT_EQ(r.report.find("probe")->restarts, 1);
  EXPECT_EQ(r.report.end, LaunchEnd::REQUIRED_EXITED);
  EXPECT_EQ(r.report.exit_code, 4);
  EXPECT_TRUE(r.report.find("server")->stopped);
}

TEST_F(SupervisorTest, SigintEscalatesToSigtermThenSigkill) {
  // "stubborn" ignores SIGINT and SIGTERM, "term" ignores only SIGINT, "polite" obeys SIGINT.
  // "trigger" sends SIGINT to the launcher (this test process) once both traps are set.
  struct sigaction before {};
  sigaction(SIGINT, nullptr, &before);
  const Result r = runLaunch(R"(
shutdown_timeout: 0.3
processes:
  - name: stubborn
    command: [sh, -c, "trap '' INT TERM; touch {dir}/r1; while :; do sleep 0.05; done"]
  - name: term
    command: [sh, -c, "trap '' INT; touch {dir}/r2; while :; do sleep 0.05; done"]
  - name: polite
    command: [sleep, "10"]
  - name: trigger
    command: [sh, -c, "while [ ! -f {dir}/r1 ] || [ ! -f {dir}/r2 ]; do sleep 0.01; done; kill -INT $PPID"]
)");
  EXPECT_EQ(r.report.end, LaunchEnd::SIGNAL);
  EXPECT_EQ(r.report.exit_code, 0);  // everything was stopped by the user

  const ProcessReport* stubborn = r.report.find("stubborn");
  EXPECT_EQ(stubborn->outcome, ProcessOutcome::SIGNALED);
  EXPECT_EQ(stubborn->signal, SIGKILL);
  EXPECT_EQ(stubborn->strongest_stop_signal, SIGKILL);
  EXPECT_TRUE(stubborn->stopped);

  const ProcessReport* term = r.report.find("term");
  EXPECT_EQ(term->signal, SIGTERM);
  EXPECT_EQ(term->strongest_stop_signal, SIGTERM);

  const ProcessReport* polite = r.report.find("polite");
  EXPECT_EQ(polite->signal, SIGINT);
  EXPECT_EQ(polite->strongest_stop_signal, SIGINT);

  EXPECT_THAT(r.log, HasSubstr("received SIGINT"));
  EXPECT_THAT(r.log, HasSubstr("still running after 0.3 s: stubborn, term"));
  EXPECT_THAT(r.log, HasSubstr("; sending SIGTERM"));
  EXPECT_THAT(r.log, HasSubstr("still running after 0.3 s: stubborn; sending SIGKILL"));
  EXPECT_THAT(r.log, HasSubstr("stubborn  stopped with SIGKILL, killed by SIGKILL"));

  // The launcher's own SIGINT disposition is restored.
  struct sigaction after {};
  sigaction(SIGINT, nullptr, &after);
  EXPECT_EQ(after.sa_handler, before.sa_handler);
}

TEST_F(SupervisorTest, SigtermToLauncherAlsoStops) {
  const Result r = runLaunch(R"(
processes:
  - {name: server, command: [sleep, "10"]}
  - {name: trigger, command: [sh, -c, "kill -TERM $PPID"]}
)");
  EXPECT_EQ(r.report.end, LaunchEnd::SIGNAL);
  EXPECT_EQ(r.report.exit_code, 0);
  EXPECT_EQ(r.report.find("server")->signal, SIGINT);  // children get SIGINT first anyway
  EXPECT_THAT(r.log, HasSubstr("received SIGTERM"));
}

TEST_F(SupervisorTest, RepeatedShutdownRequestsEscalateImmediately) {
  // A long shutdown_timeout: only the repeated requests can get the stubborn child killed.
  LaunchDescription launch = parse(R"(
shutdown_timeout: 60
processes:
  - name: stubborn
    command: [sh, -c, "trap '' INT TERM; touch {dir}/ready; while :; do sleep 0.05; done"]
)");
  std::atomic<Supervisor*> supervisor{nullptr};
  std::atomic<bool> done{false};
  std::thread requester([&] {
    while (!done && (supervisor == nullptr || !fs::exists(dir_.file("ready")))) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (int i = 0; i < 3 && !done; ++i) {
      supervisor.load()->requestShutdown();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  SupervisorOptions options = makeOptions();
  options.handle_signals = false;
  const Result r = runSupervisor(std::move(launch), options, &supervisor);
  done = true;
  requester.join();
  const ProcessReport& stubborn = r.report.processes[0];
  EXPECT_EQ(stubborn.signal, SIGKILL);
  EXPECT_EQ(stubborn.strongest_stop_signal, SIGKILL);
  EXPECT_EQ(r.report.end, LaunchEnd::SIGNAL);
  EXPECT_THAT(r.log, HasSubstr("received shutdown request again; sending SIGKILL now"));
}

TEST_F(SupervisorTest, ShutdownRequestedBeforeRunStartsNothing) {
  Supervisor supervisor(parse("processes:\n  - {name: a, command: [sleep, '10']}\n"),
                        makeOptions());
  supervisor.requestShutdown();
  const LaunchReport report = supervisor.run();
  EXPECT_EQ(report.end, LaunchEnd::SIGNAL);
  EXPECT_EQ(report.exit_code, 0);
  EXPECT_TRUE(report.processes[0].pids.empty());
  EXPECT_TRUE(report.processes[0].stopped);
  EXPECT_THROW(supervisor.run(), std::runtime_error);  // one run per Supervisor
}

TEST_F(SupervisorTest, EnvironmentAndVendorReachTheChild) {
  setenv("LAUNCH_TEST_PARENT", "inherited", 1);
  unsetenv("AUV_DDS");
  const Result r = runLaunch(R"(
environment: {AUV_DOMAIN_ID: "7", SHARED: launch}
processes:
  - name: fast
    command: [sh, -c, 'echo "dds=$AUV_DDS domain=$AUV_DOMAIN_ID shared=$SHARED foo=$FOO parent=$LAUNCH_TEST_PARENT"']
    vendor: fastdds
    environment: {SHARED: process, FOO: bar, AUV_DDS: cyclonedds}
  - name: plain
    command: [sh, -c, 'echo "dds=${AUV_DDS:-unset} domain=$AUV_DOMAIN_ID shared=$SHARED foo=${FOO:-unset}"']
)");
  unsetenv("LAUNCH_TEST_PARENT");
  EXPECT_THAT(r.out,
              HasSubstr("[fast] dds=fastdds domain=7 shared=process foo=bar parent=inherited\n"));
  EXPECT_THAT(r.out, HasSubstr("[plain] dds=unset domain=7 shared=launch foo=unset\n"));
}

TEST_F(SupervisorTest, ComponentsRunThroughAuvWithParamsFilesThatAreRemoved) {
  dir_.write("params/base.yaml", "talker: {rate_hz: 1.0}\n");
  const Result r = runLaunch(R"(
processes:
  - name: talker
    component: demo_talker
    vendor: cyclonedds
    params_file: params/base.yaml
    parameters: {rate_hz: 10.0}
  - name: vehicle
    components:
      - {component: demo_talker, name: talker2, parameters: {rate_hz: 2.0}}
      - {component: demo_listener, name: listener2}
)");
  EXPECT_EQ(r.report.exit_code, 0);
  const std::string tmp = dir_.file("tmp");
  EXPECT_THAT(r.out,
              HasSubstr("[talker] argv: run demo_talker:talker --params " +
                        dir_.file("params/base.yaml") + " --params " + tmp + "/auv-launch-"));
  EXPECT_THAT(r.out, HasSubstr("[talker] dds: cyclonedds\n"));
  EXPECT_THAT(r.out, HasSubstr("[talker]   rate_hz: 10.0\n"));
  EXPECT_THAT(r.out, HasSubstr("[vehicle] argv: run demo_talker:talker2 demo_listener:listener2 "
                               "--params " +
                               tmp + "/auv-launch-"));
  EXPECT_THAT(r.out, HasSubstr("[vehicle] dds: unset\n"));
  EXPECT_THAT(r.out, HasSubstr("[vehicle] talker2:\n[vehicle]   rate_hz: 2.0\n"));
  EXPECT_TRUE(fs::is_empty(tmp)) << "generated params files were not removed";
}

TEST_F(SupervisorTest, OutputIsPrefixedLineByLinePerStream) {
  const Result r = runLaunch(R"(
processes:
  - name: p
    command: [sh, -c, "echo out1; echo err1 >&2; printf 'a\nb\n\nno-newline'; printf 'e-partial' >&2"]
  - name: longer_name
    command: [sh, -c, "for i in 1 2 3; do echo line$i; done"]
)");
  // Lines of different processes may interleave, lines themselves never do.
  const std::vector<std::string> out = lines(r.out);
  const auto linesOf = [&out](const std::string& prefix) {
    std::vector<std::string> selected;
    for (const std::string& line : out) {
      if (line.rfind(prefix, 0) == 0) selected.push_back(line);
    }
    return selected;
  };
  EXPECT_THAT(linesOf("[p] "), ElementsAre("[p] out1", "[p] a", "[p] b", "[p] ", "[p] no-newline"));
  EXPECT_THAT(linesOf("[longer_name] "),
              ElementsAre("[longer_name] line1", "[longer_name] line2", "[longer_name] line3"));
  EXPECT_THAT(lines(r.err), ElementsAre("[p] err1", "[p] e-partial"));
  for (const std::string& line : out) {
    EXPECT_TRUE(line.rfind("[p] ", 0) == 0 || line.rfind("[longer_name] ", 0) == 0) << line;
  }
}

TEST_F(SupervisorTest, LargeOutputIsCopiedCompletely) {
  // More than a pipe buffer, written by a process that exits right away.
  const Result r = runLaunch("processes:\n  - {name: n, command: [seq, '1', '30000']}\n");
  const std::vector<std::string> out = lines(r.out);
  ASSERT_EQ(out.size(), 30000u);
  EXPECT_EQ(out.front(), "[n] 1");
  EXPECT_EQ(out[12344], "[n] 12345");
  EXPECT_EQ(out.back(), "[n] 30000");
}

TEST_F(SupervisorTest, LeftoversOfAProcessGroupAreKilledAndReaped) {
  // The child exits leaving a background grandchild holding its stdout open.
  const Result r = runLaunch(R"(
processes:
  - name: parent
    command: [sh, -c, "sleep 10 & echo $! > {dir}/grandchild; echo bye"]
)");
  EXPECT_EQ(r.report.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("[parent] bye\n"));
  const pid_t grandchild = std::stoi(readFile(dir_.file("grandchild")));
  EXPECT_EQ(kill(grandchild, 0), -1) << "grandchild " << grandchild << " survived";
  EXPECT_EQ(errno, ESRCH);
}

TEST_F(SupervisorTest, ShutdownReapsGrandchildrenOfStoppedProcesses) {
  const Result r = runLaunch(R"(
shutdown_timeout: 0.2
processes:
  - name: tree
    command: [sh, -c, "trap '' INT TERM; sleep 10 & echo $! > {dir}/grandchild; while :; do sleep 0.05; done"]
  - {name: probe, command: [sh, -c, "while [ ! -s {dir}/grandchild ]; do sleep 0.01; done"], required: true}
)");
  EXPECT_EQ(r.report.exit_code, 0);
  EXPECT_EQ(r.report.find("tree")->signal, SIGKILL);
  const pid_t grandchild = std::stoi(readFile(dir_.file("grandchild")));
  EXPECT_EQ(kill(grandchild, 0), -1);
  EXPECT_EQ(errno, ESRCH);
}

TEST_F(SupervisorTest, ConstructorRejectsMissingAuvExecutable) {
  SupervisorOptions options = makeOptions();
  options.auv_executable.clear();
  EXPECT_THROW(Supervisor(parse("processes:\n  - {name: a, component: c}\n"), options),
               std::invalid_argument);
  options.poll_interval = 0.0;
  EXPECT_THROW(options.check(), std::invalid_argument);
  for (int fd : {options.stdout_fd, options.stderr_fd, options.log_fd}) close(fd);
}

// ---------------------------------------------------------------------------------------------
// `auv launch` entry point.

TEST(LaunchMainTest, DryRunPrintsCommandsAndEnvironment) {
  ScratchDir dir;
  dir.write("params/talker.yaml", "talker: {rate_hz: 5.0}\n");
  const std::string file = dir.write("demo.yaml", kFullExample);
  ::testing::internal::CaptureStdout();
  const int code = launchMain({file, "--dry-run"}, "/opt/auv/bin/auv");
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, 0);
  EXPECT_THAT(out, HasSubstr("talker:\n  command: /opt/auv/bin/auv run demo_talker:talker "
                             "--params " +
                             dir.file("params/talker.yaml") + " --params "));
  EXPECT_THAT(out, HasSubstr("  environment: AUV_DDS=fastdds AUV_DOMAIN_ID=7 FOO=bar\n"));
  EXPECT_THAT(out, HasSubstr("probe:\n  command: /opt/auv/bin/auv topic echo /chatter --once\n"));
  EXPECT_THAT(out, HasSubstr("  inline parameters ("));
  EXPECT_THAT(out, HasSubstr("      rate_hz: 10.0\n"));
  EXPECT_THAT(out, HasSubstr("  restart: on-failure (max_restarts: 3, restart_delay: 0.5 s)\n"));
}

TEST(LaunchMainTest, BadInputGivesOneErrorLine) {
  ScratchDir dir;
  const std::string file =
      dir.write("bad.yaml", "processes:\n  - {name: a, command: [x], restart: sometimes}\n");
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(launchMain({file}, "/bin/auv"), 2);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_THAT(err, StartsWith("auv launch: " + file + ": processes[0].restart: expected one of"));
  EXPECT_EQ(lines(err).size(), 1u);

  for (const std::vector<std::string>& args :
       {std::vector<std::string>{}, {"--bogus", file}, {file, "extra.yaml"}}) {
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(launchMain(args, "/bin/auv"), 2);
    const std::string usage = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(lines(usage).size(), 1u) << usage;
    EXPECT_THAT(usage, AllOf(StartsWith("auv launch: "), HasSubstr("usage: auv launch")));
  }
}

// The mapping's resolution and the one planning and mission accept must agree, or both reject
// every map update: vehicle.yaml sets all three from one argument.
TEST(ShippedLaunchTest, VehicleGivesEveryMapReaderTheMappingsResolution) {
  const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/vehicle.yaml";
  for (const char* resolution : {"", "0.25"}) {
    SCOPED_TRACE(resolution);
    std::map<std::string, std::string> arguments;
    if (*resolution) arguments["map_resolution"] = resolution;
    const LaunchDescription launch = parseLaunchFile(file, arguments);
    std::map<std::string, double> seen;  // node -> the resolution it builds or expects
    for (const ProcessDescription& process : launch.processes) {
      for (const ComponentDescription& c : process.components) {
        const char* key = c.component == "mapping" ? "resolution" : "map_resolution";
        if (c.component == "mapping" || c.component == "planning" || c.component == "mission") {
          ASSERT_TRUE(c.parameters[key]) << c.node_name << " has no " << key;
          seen[c.node_name] = c.parameters[key].as<double>();
        }
      }
    }
    const double expected = *resolution ? 0.25 : 0.5;
    EXPECT_EQ(seen, (std::map<std::string, double>{
                        {"mapping", expected}, {"planning", expected}, {"mission", expected}}));
  }
}

TEST(ShippedLaunchTest, VehicleGivesTheMappingItsInitialMap) {
  const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/vehicle.yaml";
  for (const char* initial_map : {"", "maps/site.bt"}) {
    SCOPED_TRACE(initial_map);
    std::map<std::string, std::string> arguments;
    if (*initial_map) arguments["initial_map"] = initial_map;
    const LaunchDescription launch = parseLaunchFile(file, arguments);
    std::string given = "(no mapping)";
    bool align = false;
    for (const ProcessDescription& process : launch.processes) {
      for (const ComponentDescription& c : process.components) {
        if (c.component != "mapping") continue;
        given = c.parameters["initial_map"].as<std::string>();
        align = c.parameters["align_initial_map"].as<bool>();
      }
    }
    EXPECT_EQ(given, initial_map);
    EXPECT_TRUE(align) << "an earlier visit's map is aligned before it is trusted";
  }
  const LaunchDescription known =
      parseLaunchFile(file, {{"initial_map", "true.bt"}, {"align_initial_map", "false"}});
  bool align = true;
  for (const ProcessDescription& process : known.processes)
    for (const ComponentDescription& c : process.components)
      if (c.component == "mapping") align = c.parameters["align_initial_map"].as<bool>();
  EXPECT_FALSE(align);
}

// The campaign's baseline: replanning:= reaches the planner (default: the paper's repair).
TEST(ShippedLaunchTest, VehicleGivesThePlannerItsReplanningMode) {
  const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/vehicle.yaml";
  for (const std::string mode : {"", "scratch"}) {
    SCOPED_TRACE(mode);
    std::map<std::string, std::string> arguments;
    if (!mode.empty()) arguments["replanning"] = mode;
    const LaunchDescription launch = parseLaunchFile(file, arguments);
    std::string given = "(no planning)";
    for (const ProcessDescription& process : launch.processes) {
      for (const ComponentDescription& c : process.components) {
        if (c.component == "planning") given = c.parameters["replanning"].as<std::string>();
      }
    }
    EXPECT_EQ(given, mode.empty() ? "repair" : mode);
  }
}

// record:=true records every topic into the run's bag folder with `auv bag record`, in a
// process of its own that restarts (into a new bag) without touching the autonomy.
TEST(ShippedLaunchTest, VehicleRecordsABagOnlyWhenAsked) {
  const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/vehicle.yaml";
  const auto bagProcess = [](const LaunchDescription& launch) -> const ProcessDescription* {
    for (const ProcessDescription& process : launch.processes)
      if (process.name == "bag") return &process;
    return nullptr;
  };
  EXPECT_EQ(bagProcess(parseLaunchFile(file, {})), nullptr);
  const LaunchDescription launch =
      parseLaunchFile(file, {{"record", "true"}, {"run_dir", "runs/r1"}, {"vendor", "fastdds"}});
  const ProcessDescription* bag = bagProcess(launch);
  ASSERT_NE(bag, nullptr);
  EXPECT_EQ(bag->command, (std::vector<std::string>{"auv", "bag", "record", "-a", "-o",
                                                    "runs/r1/bags/", "--vendor", "fastdds"}));
  EXPECT_EQ(bag->restart, RestartPolicy::ON_FAILURE);
  EXPECT_FALSE(bag->required);
}

// viewer:=true adds the Foxglove bridge, bound to loopback unless told otherwise, restarted on
// failure and never required, to the vehicle and to the shore.
TEST(ShippedLaunchTest, ViewerAddsTheBridgeOnLoopback) {
  for (const char* name : {"vehicle.yaml", "shore.yaml"}) {
    SCOPED_TRACE(name);
    const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/" + name;
    std::map<std::string, std::string> arguments = {{"survey", "surveys/s1"}};
    if (std::string(name) == "vehicle.yaml") arguments.clear();
    const auto bridge = [](const LaunchDescription& launch) -> const ProcessDescription* {
      for (const ProcessDescription& process : launch.processes)
        if (process.name == "foxglove_bridge") return &process;
      return nullptr;
    };
    EXPECT_EQ(bridge(parseLaunchFile(file, arguments)), nullptr);
    arguments["viewer"] = "true";
    const LaunchDescription launch = parseLaunchFile(file, arguments);
    const ProcessDescription* process = bridge(launch);
    ASSERT_NE(process, nullptr);
    ASSERT_EQ(process->components.size(), 1u);
    EXPECT_EQ(process->components[0].component, "foxglove_bridge");
    EXPECT_EQ(process->components[0].parameters["address"].as<std::string>(), "127.0.0.1");
    EXPECT_EQ(process->restart, RestartPolicy::ON_FAILURE);
    EXPECT_FALSE(process->required);
  }
}

// Like ROS_DOMAIN_ID for ros2 launch: an exported AUV_DOMAIN_ID / AUV_DDS is every shipped
// launch file's default domain and vendor, and domain:= / vendor:= still win.
TEST(ShippedLaunchTest, ExportedDomainAndVendorAreTheDefaults) {
  for (const char* name : {"sim.yaml", "vehicle.yaml", "shore.yaml"}) {
    SCOPED_TRACE(name);
    const std::string file = std::string(AUV_SHIPPED_LAUNCH_DIR) + "/" + name;
    std::map<std::string, std::string> arguments;
    if (std::string(name) == "shore.yaml") arguments["survey"] = "surveys/s1";
    auto check = [&](const std::map<std::string, std::string>& extra, const char* domain,
                     DdsVendor vendor) {
      std::map<std::string, std::string> all = arguments;
      all.insert(extra.begin(), extra.end());
      const LaunchDescription launch = parseLaunchFile(file, all);
      EXPECT_EQ(launch.environment.at("AUV_DOMAIN_ID"), domain);
      ASSERT_FALSE(launch.processes.empty());
      for (const ProcessDescription& process : launch.processes) {
        EXPECT_EQ(process.vendor, vendor) << process.name;
      }
    };
    ::unsetenv("AUV_DOMAIN_ID");
    ::unsetenv("AUV_DDS");
    check({}, "0", DdsVendor::CYCLONEDDS);
    ::setenv("AUV_DOMAIN_ID", "17", 1);
    ::setenv("AUV_DDS", "fastdds", 1);
    check({}, "17", DdsVendor::FASTDDS);
    check({{"domain", "5"}, {"vendor", "cyclonedds"}}, "5", DdsVendor::CYCLONEDDS);
    ::unsetenv("AUV_DOMAIN_ID");
    ::unsetenv("AUV_DDS");
  }
}

TEST(LaunchMainTest, RunsTheLaunchAndReturnsItsExitCode) {
  ScratchDir dir;
  const std::string file =
      dir.write("x.yaml", "processes:\n  - {name: a, command: [sh, -c, 'echo hi; exit 4']}\n");
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int code = launchMain({file}, "/bin/auv");
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 4);
  EXPECT_THAT(out, HasSubstr("[a] hi\n"));
  EXPECT_THAT(err, HasSubstr("[launch] exit code 4"));
}

}  // namespace
}  // namespace auv::bringup
