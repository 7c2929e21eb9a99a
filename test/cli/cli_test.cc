// The `auv` CLI as a user runs it, across vendors: Fast DDS publisher -> Cyclone echo and the
// reverse, discovery of both vendors' nodes, a transient-local late joiner, launch with
// composition, and one clear line + non-zero exit for bad input. Domains 170..189.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

namespace {

using namespace std::chrono_literals;

struct Result {
  int exit_code = -1;
  std::string out;  // stdout and stderr together
};

// Runs a shell command line with `auv` resolved to the executable under test.
Result run(const std::string& env, const std::string& args) {
  const std::string command = env + " " + AUV_EXECUTABLE + " " + args + " 2>&1";
  Result r;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

// A background `auv` process, stopped with SIGINT at scope exit.
class Background {
 public:
  Background(const std::string& env, const std::string& args) {
    pid_ = fork();
    if (pid_ == 0) {
      setpgid(0, 0);
      execl("/bin/sh", "sh", "-c",
            ("exec env " + env + " " + AUV_EXECUTABLE + " " + args + " >/dev/null 2>&1").c_str(),
            nullptr);
      _exit(127);
    }
  }
  ~Background() { stop(); }
  int stop() {
    if (pid_ <= 0) return status_;
    kill(pid_, SIGINT);
    int status = 0;
    for (int i = 0; i < 100 && waitpid(pid_, &status, WNOHANG) == 0; ++i)
      std::this_thread::sleep_for(100ms);
    if (waitpid(pid_, &status, WNOHANG) == 0) {
      kill(-pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
    pid_ = -1;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return status_;
  }

 private:
  pid_t pid_ = -1;
  int status_ = -1;
};

std::string env(const char* vendor, int domain) {
  return std::string("AUV_DDS=") + vendor + " AUV_DOMAIN_ID=" + std::to_string(domain);
}

struct Pair {
  const char* pub;
  const char* sub;
  int domain;
};

class CliPubEchoTest : public testing::TestWithParam<Pair> {};

TEST_P(CliPubEchoTest, EchoShowsWhatPubSendsAcrossVendors) {
  const Pair p = GetParam();
  Background pub(env(p.pub, p.domain), "topic pub /chatter auv::msg::String '{data: from " +
                                           std::string(p.pub) + "}' --rate 10");
  const Result echo = run(env(p.sub, p.domain), "topic echo /chatter --once --timeout 20");
  EXPECT_EQ(echo.exit_code, 0) << echo.out;
  EXPECT_NE(echo.out.find("data: from " + std::string(p.pub)), std::string::npos) << echo.out;
  const Result field = run(env(p.sub, p.domain), "topic echo /chatter --once --field data");
  EXPECT_EQ(field.out.rfind("from " + std::string(p.pub), 0), 0u) << field.out;
}

INSTANTIATE_TEST_SUITE_P(Vendors, CliPubEchoTest,
                         testing::Values(Pair{"fastdds", "cyclonedds", 170},
                                         Pair{"cyclonedds", "fastdds", 171},
                                         Pair{"fastdds", "fastdds", 172},
                                         Pair{"cyclonedds", "cyclonedds", 173}));

TEST(CliTest, ListAndInfoShowNodesOfBothVendors) {
  Background talker(env("fastdds", 175), "run demo_talker:fast_talker");
  Background listener(env("cyclonedds", 175), "run demo_listener:cyc_listener");
  // Both processes must be up before a snapshot can show them (startup is slow under load).
  Result nodes;
  for (int i = 0; i < 20; ++i) {
    nodes = run(env("cyclonedds", 175), "node list --wait 1");
    if (nodes.out.find("/fast_talker") != std::string::npos &&
        nodes.out.find("/cyc_listener") != std::string::npos)
      break;
  }
  for (const char* vendor : {"cyclonedds", "fastdds"}) {
    SCOPED_TRACE(vendor);
    const Result list = run(env(vendor, 175), "topic list -t --wait 4");
    EXPECT_NE(list.out.find("/chatter [auv::msg::String]"), std::string::npos) << list.out;
    EXPECT_NE(list.out.find("/demo/status [auv::msg::MissionStatus]"), std::string::npos)
        << list.out;
    // A new participant's endpoints can take one discovery heartbeat (Fast DDS: 3 s) to reach
    // an inspector when its first announcement races the match, which is longer than the 1.5 s
    // for which `topic info` waits for the count to settle: a snapshot may come early, so ask
    // again (at most 4 times) before judging what it shows.
    Result info;
    for (int attempt = 0; attempt < 4; ++attempt) {
      info = run(env(vendor, 175), "topic info /chatter -v --wait 10");
      if (info.out.find("Publisher count: 1") != std::string::npos &&
          info.out.find("Subscription count: 1") != std::string::npos)
        break;
    }
    EXPECT_EQ(info.exit_code, 0) << info.out;
    EXPECT_NE(info.out.find("Publisher count: 1"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("Subscription count: 1"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("Node name: fast_talker"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("Node name: cyc_listener"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("Vendor: fastdds"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("Vendor: cyclonedds"), std::string::npos) << info.out;
    nodes = run(env(vendor, 175), "node list --wait 4");
    EXPECT_NE(nodes.out.find("/fast_talker"), std::string::npos) << nodes.out;
    EXPECT_NE(nodes.out.find("/cyc_listener"), std::string::npos) << nodes.out;
  }
}

TEST(CliTest, HzAndBwMeasureAPublisherOfTheOtherVendor) {
  Background pub(env("fastdds", 179), "topic pub /beat String '{data: 0123456789}' --rate 20");
  const Result hz = run(env("cyclonedds", 179), "topic hz /beat --duration 4 --timeout 20");
  EXPECT_EQ(hz.exit_code, 0) << hz.out;
  const auto at = hz.out.rfind("average rate: ");
  ASSERT_NE(at, std::string::npos) << hz.out;
  const double rate = std::stod(hz.out.substr(at + 14));
  EXPECT_GT(rate, 10.0) << hz.out;  // published at 20 Hz; generous for a loaded CI machine
  EXPECT_LT(rate, 30.0) << hz.out;
  const Result bw = run(env("cyclonedds", 179), "topic bw /beat --duration 3 --timeout 20");
  EXPECT_EQ(bw.exit_code, 0) << bw.out;
  // 4-byte encapsulation + 4-byte length + 10 characters + NUL = 19 bytes per message.
  EXPECT_NE(bw.out.find("mean: 0.02 KiB"), std::string::npos) << bw.out;
}

TEST(CliTest, LateJoinerOfOtherVendorGetsLatchedStatus) {
  // The listener (Cyclone) publishes its count on /demo/status, transient local; the talker
  // stops after a few messages, then a Fast DDS echo joins late and must still get it.
  Background listener(env("cyclonedds", 176), "run demo_listener:latched");
  const Result pub =
      run(env("fastdds", 176),
          "topic pub /chatter String '{data: ping}' --times 5 --rate 5 --wait-matching 20");
  ASSERT_EQ(pub.exit_code, 0) << pub.out;
  std::this_thread::sleep_for(500ms);
  const Result echo =
      run(env("fastdds", 176), "topic echo /demo/status --once --field message --timeout 10");
  EXPECT_EQ(echo.exit_code, 0) << echo.out;
  EXPECT_NE(echo.out.find("last: ping"), std::string::npos) << echo.out;
}

TEST(CliTest, LaunchComposesAndStopsCleanly) {
  const std::string launch = testing::TempDir() + "cli_test_launch.yaml";
  FILE* f = fopen(launch.c_str(), "w");
  fputs(
      "environment: {AUV_DOMAIN_ID: \"177\"}\n"
      "processes:\n"
      "  - name: pair\n"
      "    vendor: fastdds\n"
      "    components:\n"
      "      - {component: demo_talker, name: t, parameters: {rate_hz: 20.0, text: composed}}\n"
      "      - {component: demo_listener, name: l}\n"
      "  - name: probe\n"
      "    vendor: cyclonedds\n"
      "    command: [auv, topic, echo, /demo/status, --once, --field, message, --timeout, '20']\n"
      "    required: true\n",
      f);
  fclose(f);
  const Result r = run("", "launch " + launch);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("[probe] heard"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("composed #"), std::string::npos) << r.out;
}

TEST(CliTest, BadInputGivesOneClearLineAndNonZeroExit) {
  struct Case {
    std::string args;
    std::string expected;
    int code;
  };
  const std::vector<Case> cases = {
      {"topic pub /chatter NoSuchType '{}'", "unknown message type 'NoSuchType'", 2},
      {"topic pub /chatter String '{data: [unclosed'", "malformed YAML", 2},
      {"topic pub /chatter String '{dta: x}'", "unknown field 'dta'", 2},
      {"topic pub /chatter Time '{sec: abc}'", "field 'sec': expected an integer, got 'abc'", 2},
      {"topic pub 'bad topic' String '{}'", "invalid topic name", 2},
      {"topic echo /nobody --timeout 1", "no publisher on /nobody within 1 s", 1},
      {"topic frobnicate", "unknown command 'topic frobnicate'", 2},
      // Input errors exit 2 whatever the command (docs/architecture.md, errors and exit codes).
      {"run no_such_component", "unknown component 'no_such_component'", 2},
      {"run demo_talker -p rate_hz:=fast", "rate_hz", 2},
      {"run demo_talker -p rate_hz:=0 --help", "rate_hz", 2},
      {"run recorder", "parameter root: empty", 2},
      {"launch /nonexistent/launch.yaml", "/nonexistent/launch.yaml", 2},
  };
  for (const Case& c : cases) {
    const Result r = run(env("cyclonedds", 178), c.args);
    EXPECT_EQ(r.exit_code, c.code) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expected), std::string::npos) << c.args << "\n" << r.out;
  }
  const Result r = run("AUV_DDS=bogus", "topic list");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("unknown DDS vendor 'bogus'"), std::string::npos) << r.out;
}

TEST(CliTest, RunHelpListsTheComponentsParametersWithTheirValues) {
  const Result r = run(env("cyclonedds", 180), "run demo_talker -p rate_hz:=5 --help");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto rate = r.out.find("rate_hz:");
  ASSERT_NE(rate, std::string::npos) << r.out;
  EXPECT_NE(r.out.find("value: 5", rate), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("source: command line (-p)", rate), std::string::npos) << r.out;
  const Result bad = run(env("cyclonedds", 180), "run demo_talker -p rate_hz:=fast --help");
  EXPECT_EQ(bad.exit_code, 2) << bad.out;  // bad input, as `auv run` without --help
  EXPECT_NE(bad.out.find("rate_hz"), std::string::npos) << bad.out;
}

// Every command answers -h/--help with its usage and exit 0, also from an environment without
// install/setup.bash (the installed programs find their libraries by their own run path).
TEST(CliTest, EveryCommandAnswersHelpWithoutTheWorkspaceEnvironment) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--help", "usage: auv <command>"},
      {"topic --help", "usage: auv topic"},
      {"topic list -h", "usage: auv topic"},
      {"node --help", "usage: auv node list"},
      {"interface --help", "usage: auv interface"},
      {"run --help", "demo_talker"},
      {"launch --help", "usage: auv launch"},
      {"sim --help", "usage: auv sim"},
      {"mission --help", "usage: auv mission"},
      {"recon --help", "usage: auv recon"},
      {"recon pull --help", "usage: auv recon pull"},
  };
  for (const auto& [args, expected] : cases) {
    const Result r = run("env -i PATH=/usr/bin:/bin", args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(expected), std::string::npos) << args << "\n" << r.out;
  }
}

// `auv <command> <sub>` runs auv-<command>-<sub> where it exists (auv-recon-pull, a lean
// program), else auv-<command> with <sub> as its first argument; options are never <sub>.
TEST(CliTest, SubcommandProgramIsPreferredOverTheCommandProgram) {
  char pattern[] = "/tmp/auv-cli-sub-XXXXXX";
  const std::string dir = mkdtemp(pattern);
  const auto script = [&](const std::string& name, const std::string& tag) {
    const std::string path = dir + "/" + name;
    FILE* f = fopen(path.c_str(), "w");
    fprintf(f, "#!/bin/sh\necho \"%s:$*\"\n", tag.c_str());
    fclose(f);
    chmod(path.c_str(), 0755);
  };
  script("auv-probetool", "whole");
  script("auv-probetool-fast", "lean");
  const std::string path_env = "PATH=" + dir + ":$PATH";
  EXPECT_EQ(run(path_env, "probetool fast a b").out, "lean:a b\n");
  EXPECT_EQ(run(path_env, "probetool slow a").out, "whole:slow a\n");
  EXPECT_EQ(run(path_env, "probetool --help").out, "whole:--help\n");
  std::remove((dir + "/auv-probetool").c_str());
  std::remove((dir + "/auv-probetool-fast").c_str());
  rmdir(dir.c_str());
}

}  // namespace
