// `auv mission start | status | abort`: talk to the mission handler over DDS.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/node.h"
#include "auv/mission/mission_executive.h"
#include "auv/mission/mission_plan.h"
#include "auv/mission/tools/mission_cli.h"

namespace auv::mission {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct UsageError : config::ConfigError {
  using config::ConfigError::ConfigError;
};

/// `--name value` options and `--flag`s of one command; anything else is positional.
struct Options {
  std::vector<std::string> positional;
  std::map<std::string, std::string> values;
  std::vector<std::string> flags;

  Options(const std::vector<std::string>& args, const std::vector<std::string>& valued,
          const std::vector<std::string>& known_flags) {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (arg.rfind("--", 0) != 0) {
        positional.push_back(arg);
      } else if (std::find(valued.begin(), valued.end(), arg) != valued.end()) {
        if (i + 1 >= args.size()) throw UsageError(arg + " needs a value");
        values[arg] = args[++i];
      } else if (std::find(known_flags.begin(), known_flags.end(), arg) != known_flags.end()) {
        flags.push_back(arg);
      } else {
        throw UsageError("unknown option '" + arg + "'");
      }
    }
  }
  bool flag(const std::string& name) const {
    return std::find(flags.begin(), flags.end(), name) != flags.end();
  }
  double seconds(const std::string& name, double fallback) const {
    auto it = values.find(name);
    if (it == values.end()) return fallback;
    try {
      std::size_t used = 0;
      const double value = std::stod(it->second, &used);
      if (used == it->second.size() && value > 0) return value;
    } catch (const std::exception&) {
    }
    throw UsageError(name + ": '" + it->second + "' is not a positive number of seconds");
  }
};

std::chrono::milliseconds toMilliseconds(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
}

std::string describe(const msg::MissionStatus& s) {
  std::string text = s.mission_id() + ": " + toString(s.state());
  if (s.current_query_index() >= 0) {
    text += " (query " + std::to_string(s.current_query_index() + 1) + "/" +
            std::to_string(s.query_count()) + ")";
  }
  text += " - " + s.message() + " [succeeded " + std::to_string(s.queries_succeeded()) + "/" +
          std::to_string(s.query_count()) + ", waypoints " + std::to_string(s.waypoints_reached()) +
          " reached / " + std::to_string(s.waypoints_received()) + " received / " +
          std::to_string(s.waypoints_cancelled()) + " cancelled, recoveries " +
          std::to_string(s.recoveries()) + "]";
  return text;
}

bool finished(msg::MissionState state) {
  return state == msg::MISSION_STATE_SUCCEEDED || state == msg::MISSION_STATE_FAILED ||
         state == msg::MISSION_STATE_ABORTED;
}

/// Follows mission/status. With `mission_id` empty: the newest mission seen. Prints every
/// change when `follow`; returns the last status, or nothing when none came within `timeout`.
std::optional<msg::MissionStatus> watchStatus(interfaces::Node& node, const std::string& mission_id,
                                              bool follow, double timeout_s) {
  interfaces::Executor executor;
  executor.add(node);
  std::map<std::string, msg::MissionStatus> latest;  // per mission (the topic is keyed)
  std::optional<msg::MissionStatus> shown;
  auto sub = node.createSubscription<msg::MissionStatus>(
      "mission/status", interfaces::latchedStateQos(),
      std::function<void(const msg::MissionStatus&)>(
          [&latest](const msg::MissionStatus& s) { latest[s.mission_id()] = s; }));
  const auto deadline = Clock::now() + toMilliseconds(timeout_s);
  auto choose = [&]() -> std::optional<msg::MissionStatus> {
    if (!mission_id.empty()) {
      auto it = latest.find(mission_id);
      return it == latest.end() ? std::nullopt : std::optional(it->second);
    }
    std::optional<msg::MissionStatus> newest;
    for (const auto& [id, s] : latest) {
      if (id == "none" && latest.size() > 1) continue;  // the idle placeholder
      if (!newest || interfaces::toNanoseconds(s.start_time()) >
                         interfaces::toNanoseconds(newest->start_time())) {
        newest = s;
      }
    }
    return newest;
  };
  // Latched samples arrive just after matching: give them a moment before answering.
  const auto settle = Clock::now() + 500ms;
  while (!interfaces::Executor::signalled() && Clock::now() < deadline) {
    executor.spinOnce(50ms);
    if (Clock::now() < settle) continue;
    const auto current = choose();
    if (!current) continue;
    const bool changed = !shown || shown->state() != current->state() ||
                         shown->message() != current->message() ||
                         shown->mission_id() != current->mission_id();
    shown = current;
    if (!follow) return shown;
    if (changed) std::cout << describe(*shown) << std::endl;
    if (finished(shown->state())) return shown;
  }
  return shown;
}

int fail(const std::string& command, const std::string& message, int code) {
  std::cerr << "auv mission " << command << ": " << message << "\n";
  return code;
}

std::string noHandler(const interfaces::Node& node) {
  return "no mission handler answered on domain " + std::to_string(node.domainId()) +
         " (is the vehicle stack running? check AUV_DOMAIN_ID and AUV_DDS)";
}

}  // namespace

int startMain(const std::vector<std::string>& args) {
  try {
    const Options options(args, {"--id", "--timeout", "--report"}, {"--wait"});
    if (options.positional.size() != 1) {
      throw UsageError(
          "usage: auv mission start <mission.yaml> [--id ID] [--wait] [--report RUN_DIR] "
          "[--timeout S]");
    }
    const double timeout = options.seconds("--timeout", 10);
    interfaces::Executor::installSignalHandlers();
    // A mission file the simulator is about to write (launch with auto_mission) may not
    // exist yet: wait for it as long as for the mission handler.
    const std::string& path = options.positional[0];
    const auto file_deadline = Clock::now() + toMilliseconds(timeout);
    if (!std::filesystem::exists(path)) std::cerr << "waiting for " << path << std::endl;
    while (!std::filesystem::exists(path) && Clock::now() < file_deadline &&
           !interfaces::Executor::signalled()) {
      std::this_thread::sleep_for(100ms);
    }
    const MissionPlan plan = loadMissionFile(path);  // names file and field
    msg::StartMissionRequest request;
    request.mission_id(options.values.count("--id") ? options.values.at("--id") : "");
    for (const MissionQuery& query : plan.queries)
      request.queries().push_back(toPlannerQuery(query));
    if (request.mission_id().empty()) {
      // Unique per start, so `auv mission status` never shows an older run's state for it.
      const std::time_t now = std::time(nullptr);
      char stamp[32];
      std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%S", std::gmtime(&now));
      request.mission_id(plan.name + "-" + stamp);
    }

    interfaces::Node node("auv_mission_cli");
    auto client =
        node.createClient<msg::StartMissionRequest, msg::StartMissionReply>("mission/start");
    msg::StartMissionReply reply;
    const auto status = client->call(request, &reply, toMilliseconds(timeout));
    if (status != interfaces::CallStatus::OK) return fail("start", noHandler(node), 1);
    if (reply.status().code() != msg::REPLY_CODE_OK) {
      return fail("start", "refused: " + reply.status().error_text(), 1);
    }
    std::cout << "mission '" << reply.mission_id() << "' started (" << plan.queries.size()
              << " queries)" << std::endl;
    if (!options.flag("--wait")) return 0;
    const auto last = watchStatus(node, reply.mission_id(), true, 1e9);
    if (!last || !finished(last->state())) return fail("start", "the mission did not end", 1);
    if (options.values.count("--report")) {
      // The simulator's last poses reach the disk within its flush period.
      std::this_thread::sleep_for(1500ms);
      if (reportMain({options.values.at("--report")}) != 0) return 1;
    }
    return last->state() == msg::MISSION_STATE_SUCCEEDED ? 0 : 1;
  } catch (const std::exception& error) {  // usage, mission file: 2; failures: 1
    return fail("start", error.what(), config::exitCodeFor(error));
  }
}

int statusMain(const std::vector<std::string>& args) {
  try {
    const Options options(args, {"--timeout", "--id"}, {"--follow"});
    if (!options.positional.empty()) {
      throw UsageError("usage: auv mission status [--id ID] [--follow] [--timeout S]");
    }
    interfaces::Executor::installSignalHandlers();
    interfaces::Node node("auv_mission_cli");
    const bool follow = options.flag("--follow");
    const auto last =
        watchStatus(node, options.values.count("--id") ? options.values.at("--id") : "", follow,
                    options.seconds("--timeout", follow ? 1e9 : 5));
    if (!last) return fail("status", "no mission/status received: " + noHandler(node), 1);
    if (!follow) std::cout << describe(*last) << std::endl;
    return 0;
  } catch (const std::exception& error) {
    return fail("status", error.what(), config::exitCodeFor(error));
  }
}

int abortMain(const std::vector<std::string>& args) {
  try {
    const Options options(args, {"--reason", "--timeout"}, {});
    if (!options.positional.empty()) {
      throw UsageError("usage: auv mission abort [--reason TEXT] [--timeout S]");
    }
    interfaces::Node node("auv_mission_cli");
    auto client = node.createClient<msg::TriggerRequest, msg::TriggerReply>("mission/abort");
    msg::TriggerRequest request;
    request.command(options.values.count("--reason") ? options.values.at("--reason") : "operator");
    msg::TriggerReply reply;
    if (client->call(request, &reply, toMilliseconds(options.seconds("--timeout", 10))) !=
        interfaces::CallStatus::OK) {
      return fail("abort", noHandler(node), 1);
    }
    if (reply.status().code() != msg::REPLY_CODE_OK) {
      return fail("abort", reply.status().error_text(), 1);
    }
    std::cout << reply.message() << std::endl;
    return 0;
  } catch (const std::exception& error) {
    return fail("abort", error.what(), config::exitCodeFor(error));
  }
}

}  // namespace auv::mission
