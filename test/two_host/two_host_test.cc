// Vehicle and shore on two "hosts": two network namespaces joined by a veth pair, made and
// removed by the test (skipped where namespaces are not allowed). The vehicle stack
// (bringup/launch/vehicle.yaml) runs on Cyclone DDS with bringup/config/cyclonedds-deploy.xml,
// the shore on Fast DDS with fastdds-deploy.xml; both templates are used as a user would, with
// the placeholders replaced. DDS domain 7 (the namespaces isolate it anyway).
//
// Scale (environment): AUV_TWO_HOST_RTF (simulator real-time factor, 4), AUV_TWO_HOST_RENDER_S
// (simulated seconds of camera video, 20), AUV_TWO_HOST_EXTRA_MB (a long recording added so the
// pull lasts long enough to be interrupted, 4), AUV_TWO_HOST_RATE (vehicle -> shore link rate,
// tc syntax, 4mbit), AUV_TWO_HOST_IMPAIR (auv_link_impair options, e.g. "--loss 0.05 --delay 40
// --jitter 20 --seed 7": every UDP datagram on the veth pair, both ways, from the vehicle's
// start to the end of the pull, goes through the impairer; empty: a clean link).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>

#include "netns_harness.h"

namespace auv::system_tests {
namespace {

namespace fs = std::filesystem;
constexpr const char* kDomain = "7";
constexpr const char* kVehicleName = "sparus";

std::string setting(const char* name, const char* fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : fallback;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeFile(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string source(const std::string& relative) {
  return std::string(AUV_SOURCE_DIR) + "/" + relative;
}

// Number of times `needle` occurs in `text`.
size_t count(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// The pid in the last "[launch] started <process> (pid N)" line, -1 if none.
pid_t lastStartedPid(const std::string& launch_output, const std::string& process) {
  const std::regex pattern("started " + process + " \\(pid ([0-9]+)\\)");
  pid_t pid = -1;
  for (auto it = std::sregex_iterator(launch_output.begin(), launch_output.end(), pattern);
       it != std::sregex_iterator(); ++it) {
    pid = std::stoi((*it)[1]);
  }
  return pid;
}

// A long recording in the contract's layout (random bytes stand in for video: the transfer
// does not look inside).
void writeLongRecording(const std::string& root, size_t megabytes) {
  fs::create_directories(root + "/long");
  std::mt19937_64 random(7);
  std::string block(1 << 20, '\0');
  std::ofstream out(root + "/long/long_0001.incomplete.mp4", std::ios::binary);
  for (size_t i = 0; i < megabytes; ++i) {
    for (size_t j = 0; j + 8 <= block.size(); j += 8) {
      const uint64_t word = random();
      block.replace(j, 8, reinterpret_cast<const char*>(&word), 8);
    }
    out.write(block.data(), static_cast<std::streamsize>(block.size()));
  }
  out.close();
  fs::rename(root + "/long/long_0001.incomplete.mp4", root + "/long/long_0001.mp4");
}

class TwoHostTest : public testing::Test {
 protected:
  void SetUp() override {
    std::string error;
    hosts_ = TwoHosts::create("2h", &error);
    if (hosts_ == nullptr) {
      GTEST_SKIP() << "cannot create network namespaces here (needs root, or CAP_NET_ADMIN and "
                      "CAP_SYS_ADMIN): "
                   << error;
    }
    work_ = testing::TempDir() + "two_host_" + std::to_string(getpid()) + "/";
    fs::remove_all(work_);
    fs::create_directories(work_);
  }

  void TearDown() override {
    if (hosts_ != nullptr && !HasFailure()) fs::remove_all(work_);  // kept for a post-mortem
  }

  // A deployment template with its placeholders replaced, as docs/deployment.md does with sed.
  std::string config(const std::string& templ, const std::string& out,
                     const std::vector<std::pair<std::string, std::string>>& replacements) {
    std::string text = readFile(source("bringup/config/" + templ));
    EXPECT_FALSE(text.empty()) << templ;
    for (const auto& [from, to] : replacements) {
      EXPECT_NE(text.find(from), std::string::npos) << templ << " lost its placeholder " << from;
      text = replaceAll(text, from, to);
    }
    writeFile(work_ + out, text);
    return work_ + out;
  }

  std::unique_ptr<TwoHosts> hosts_;
  std::string work_;
};

TEST_F(TwoHostTest, VehicleOnCycloneShoreOnFastDdsMissionAndPullAcrossACutLink) {
  const TwoHosts::Host& vehicle = hosts_->vehicle();
  const TwoHosts::Host& shore = hosts_->shore();
  const std::string vehicle_dds = config("cyclonedds-deploy.xml", "vehicle-cyclonedds.xml",
                                         {{"\"eth0\"", "\"" + vehicle.veth + "\""},
                                          {"192.0.2.10", vehicle.address},
                                          {"192.0.2.20", shore.address}});
  const std::string shore_dds =
      config("fastdds-deploy.xml", "shore-fastdds.xml",
             {{"192.0.2.10", shore.address}, {"192.0.2.20", vehicle.address}});
  const std::map<std::string, std::string> vehicle_env = {
      {"AUV_DOMAIN_ID", kDomain},
      {"AUV_DDS", "cyclonedds"},
      {"CYCLONEDDS_URI", "file://" + vehicle_dds}};
  const std::map<std::string, std::string> shore_env = {
      {"AUV_DOMAIN_ID", kDomain},
      {"AUV_DDS", "fastdds"},
      {"FASTRTPS_DEFAULT_PROFILES_FILE", shore_dds}};
  const std::string run = work_ + "run";
  const std::string recordings = run + "/vehicle/recordings";
  const std::string survey = work_ + "survey";

  // 0. Optionally a lossy, delaying, reordering link (ctest's two_host_lossy_link).
  std::unique_ptr<BackgroundProcess> impairer;
  const std::string impair = setting("AUV_TWO_HOST_IMPAIR", "");
  if (!impair.empty()) {
    ASSERT_STRNE(LINK_IMPAIR_EXECUTABLE, "") << "AUV_TWO_HOST_IMPAIR needs auv_link_impair "
                                                "(apt-get install libnetfilter-queue-dev)";
    for (const char* chain : {"OUTPUT", "INPUT"}) {
      const CommandResult rule = hosts_->run(
          vehicle, {},
          {"iptables", "-A", chain, std::string(chain) == "OUTPUT" ? "-o" : "-i", vehicle.veth,
           "-p", "udp", "-j", "NFQUEUE", "--queue-num", "5", "--queue-bypass"});
      ASSERT_EQ(rule.exit_code, 0) << rule.out;
    }
    std::vector<std::string> command = {LINK_IMPAIR_EXECUTABLE, "--queue", "5"};
    std::istringstream words(impair);
    for (std::string word; words >> word;) command.push_back(word);
    impairer = std::make_unique<BackgroundProcess>(vehicle, std::map<std::string, std::string>{},
                                                   command, work_ + "impair.log");
  }

  // 1. The vehicle stack with its recorder, on Cyclone DDS bound to the veth interface.
  BackgroundProcess vehicle_launch(
      vehicle, vehicle_env,
      {AUV_EXECUTABLE, "launch", source("bringup/launch/vehicle.yaml"), "world:=breakwater",
       "real_time_factor:=" + setting("AUV_TWO_HOST_RTF", "4"), "run_dir:=" + run,
       std::string("domain:=") + kDomain, "vendor:=cyclonedds",
       std::string("vehicle_name:=") + kVehicleName},
      work_ + "vehicle_launch.log");
  // The first launch on a machine generates the world (~10 s).
  ASSERT_TRUE(waitUntil(300, [&] {
    return vehicle_launch.output().find("run folder") != std::string::npos ||
           !vehicle_launch.running();
  }));
  ASSERT_TRUE(vehicle_launch.running()) << vehicle_launch.output();

  // 2. The shore (Fast DDS) sees the vehicle's topics across the link.
  const std::vector<std::string> expected_topics = {
      "/nav/odometry", "/sonar/beam", "/mission/status", "/control/status",
      std::string("/") + kVehicleName + "/recorder/fetch_chunk/request"};
  CommandResult topics;
  waitUntil(120, [&] {
    topics = hosts_->run(shore, shore_env, {AUV_EXECUTABLE, "topic", "list", "--wait", "3"});
    for (const std::string& topic : expected_topics) {
      if (topics.out.find(topic + "\n") == std::string::npos) return false;
    }
    return true;
  });
  for (const std::string& topic : expected_topics) {
    EXPECT_NE(topics.out.find(topic + "\n"), std::string::npos) << topic << "\n" << topics.out;
  }

  // 3. A short mission (one hop of 6 m along the breakwater), started from the shore.
  writeFile(work_ + "mission.yaml",
            "mission:\n"
            "  name: two_host\n"
            "  defaults: {objective: path_length, fixed_depth: true, depth: 4.0,\n"
            "             bounds: {min: [-40, -66, 0], max: [40, 66, 10]}, goal_tolerance: 2.0}\n"
            "  queries:\n"
            "    - {name: short_hop, goal: [18.0, -0.228, 4.0]}\n");
  const CommandResult mission = hosts_->run(
      shore, shore_env,
      {AUV_EXECUTABLE, "mission", "start", work_ + "mission.yaml", "--wait", "--timeout", "120"});
  EXPECT_EQ(mission.exit_code, 0) << mission.out << "\n" << vehicle_launch.output();

  // 4. The cameras' recordings of the run (the simulator renders them afterwards), plus a long
  //    one so that the pull lasts long enough to be interrupted.
  const CommandResult render =
      hosts_->run(vehicle, vehicle_env,
                  {AUV_EXECUTABLE, "sim", "render", run, "--end",
                   setting("AUV_TWO_HOST_RENDER_S", "20"), "--scale", "0.25", "--quiet"});
  ASSERT_EQ(render.exit_code, 0) << render.out;
  writeLongRecording(recordings, std::stoul(setting("AUV_TWO_HOST_EXTRA_MB", "4")));
  const std::vector<std::string> vehicle_files = listFiles(recordings);
  ASSERT_GE(vehicle_files.size(), 4u);  // left, right, forward (+ sidecars), long

  // 5. The shore pulls (bringup/launch/shore.yaml) through a slowed link; meanwhile the link is
  //    cut and restored, and the vehicle's recorder is killed and restarted by its launch.
  ASSERT_TRUE(hosts_->limitVehicleRate(setting("AUV_TWO_HOST_RATE", "4mbit")));
  BackgroundProcess pull(shore, shore_env,
                         {AUV_EXECUTABLE, "launch", source("bringup/launch/shore.yaml"),
                          std::string("vehicle:=") + kVehicleName, "survey:=" + survey,
                          std::string("domain:=") + kDomain, "vendor:=fastdds", "timeout:=60",
                          "in_flight:=2", "chunk_bytes:=65536"},
                         work_ + "pull.log");
  ASSERT_TRUE(waitUntil(180, [&] { return folderBytes(survey) > 0 || !pull.running(); }));
  ASSERT_TRUE(pull.running()) << "the pull ended before the link was cut; make it longer "
                                 "(AUV_TWO_HOST_EXTRA_MB, AUV_TWO_HOST_RATE)\n"
                              << pull.output();
  ASSERT_TRUE(hosts_->setLinkUp(false));
  std::this_thread::sleep_for(std::chrono::seconds(3));  // the outage, not a measurement
  const unsigned long long bytes_before_restore = folderBytes(survey);
  ASSERT_TRUE(hosts_->setLinkUp(true));
  ASSERT_TRUE(waitUntil(
      120, [&] { return folderBytes(survey) > bytes_before_restore || !pull.running(); }));
  ASSERT_TRUE(pull.running()) << "the pull ended before the recorder restart; make it longer "
                                 "(AUV_TWO_HOST_EXTRA_MB, AUV_TWO_HOST_RATE)\n"
                              << pull.output();
  const pid_t recorder = lastStartedPid(vehicle_launch.output(), "recorder");
  ASSERT_GT(recorder, 0) << vehicle_launch.output();
  ASSERT_EQ(kill(recorder, SIGKILL), 0);
  EXPECT_TRUE(waitUntil(60, [&] {
    return count(vehicle_launch.output(), "started recorder (pid") >= 2;
  })) << vehicle_launch.output();

  const int pull_exit = pull.waitExit(600);
  const std::string pull_output = pull.output();
  EXPECT_EQ(pull_exit, 0) << pull_output;
  EXPECT_NE(pull_output.find("pull: "), std::string::npos) << pull_output;

  // 6. Every recording and sidecar on the shore, byte-identical.
  //    The pull's own bookkeeping (manifest, lock) sits at the top of recordings/; every camera
  //    folder must hold exactly the vehicle's files (no temporary leftovers).
  std::vector<std::string> shore_files;
  for (const std::string& file : listFiles(survey + "/recordings")) {
    if (file.find('/') != std::string::npos) shore_files.push_back(file);
  }
  EXPECT_EQ(shore_files, vehicle_files) << pull_output;
  for (const std::string& file : vehicle_files) {
    const std::string expected = fileSha256(recordings + "/" + file);
    ASSERT_EQ(expected.size(), 64u) << file;
    EXPECT_EQ(fileSha256(survey + "/recordings/" + file), expected) << file;
  }
  vehicle_launch.stop();
  if (impairer) {
    // The impairment happened: the tool's counters (printed when it stops) show drops.
    ASSERT_TRUE(impairer->running()) << impairer->output();
    impairer->stop();
    const std::string counters = impairer->output();
    std::cout << "link: " << counters << std::endl;
    const std::smatch dropped = [&] {
      std::smatch match;
      std::regex_search(counters, match, std::regex("dropped ([0-9]+)"));
      return match;
    }();
    ASSERT_FALSE(dropped.empty()) << counters;
    EXPECT_GT(std::stoull(dropped[1]), 0u) << counters;
  }
}

TEST_F(TwoHostTest, FastDdsDiscoveryServerAcrossVeth) {
  const TwoHosts::Host& vehicle = hosts_->vehicle();
  const TwoHosts::Host& shore = hosts_->shore();
  const std::string server_xml =
      config("fastdds-discovery-server.xml", "server.xml", {{"192.0.2.30", vehicle.address}});
  const std::string vehicle_xml =
      config("fastdds-discovery-client.xml", "vehicle-client.xml",
             {{"192.0.2.10", vehicle.address}, {"192.0.2.30", vehicle.address}});
  const std::string shore_xml =
      config("fastdds-discovery-client.xml", "shore-client.xml",
             {{"192.0.2.10", shore.address}, {"192.0.2.30", vehicle.address}});
  BackgroundProcess server(vehicle, {}, {"fastdds", "discovery", "-x", server_xml},
                           work_ + "server.log");
  BackgroundProcess talker(vehicle,
                           {{"AUV_DOMAIN_ID", kDomain},
                            {"AUV_DDS", "fastdds"},
                            {"FASTRTPS_DEFAULT_PROFILES_FILE", vehicle_xml}},
                           {AUV_EXECUTABLE, "run", "demo_talker"}, work_ + "talker.log");
  const std::map<std::string, std::string> shore_env = {
      {"AUV_DOMAIN_ID", kDomain},
      {"AUV_DDS", "fastdds"},
      {"FASTRTPS_DEFAULT_PROFILES_FILE", shore_xml}};
  const CommandResult echo = hosts_->run(
      shore, shore_env, {AUV_EXECUTABLE, "topic", "echo", "/chatter", "--once", "--timeout", "60"});
  EXPECT_EQ(echo.exit_code, 0) << echo.out << "\n" << server.output() << talker.output();
  EXPECT_NE(echo.out.find("from demo_talker (fastdds)"), std::string::npos) << echo.out;
  // A SUPER_CLIENT sees the whole graph, not only the endpoints matching its own.
  const CommandResult list =
      hosts_->run(shore, shore_env, {AUV_EXECUTABLE, "topic", "list", "--wait", "3"});
  EXPECT_NE(list.out.find("/chatter\n"), std::string::npos) << list.out;
  EXPECT_NE(list.out.find("/demo_talker/reset/request\n"), std::string::npos) << list.out;
}

}  // namespace
}  // namespace auv::system_tests
