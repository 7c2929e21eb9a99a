#include "auv/mission/mission_progress.h"

#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "auv/config/state_file.h"
#include "auv/config/yaml_scalars.h"
#include "auv/mission/mission_executive.h"

namespace auv::mission {

bool isRunning(msg::MissionState state) {
  return state == msg::MISSION_STATE_CHECKING_READINESS ||
         state == msg::MISSION_STATE_WAITING_FOR_WAYPOINT ||
         state == msg::MISSION_STATE_EXECUTING || state == msg::MISSION_STATE_RECOVERING;
}

bool MissionProgress::running() const { return isRunning(state); }

std::optional<msg::MissionState> missionStateFromString(const std::string& name) {
  for (msg::MissionState state :
       {msg::MISSION_STATE_IDLE, msg::MISSION_STATE_CHECKING_READINESS,
        msg::MISSION_STATE_WAITING_FOR_WAYPOINT, msg::MISSION_STATE_EXECUTING,
        msg::MISSION_STATE_SUCCEEDED, msg::MISSION_STATE_FAILED, msg::MISSION_STATE_ABORTED,
        msg::MISSION_STATE_RECOVERING}) {
    if (name == toString(state)) return state;
  }
  return std::nullopt;
}

std::string toYaml(const MissionProgress& p) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "launch_id" << YAML::Value << p.launch_id;
  out << YAML::Key << "mission_id" << YAML::Value << p.mission_id;
  out << YAML::Key << "state" << YAML::Value << toString(p.state);
  out << YAML::Key << "query_index" << YAML::Value << p.query_index;
  out << YAML::Key << "start_time" << YAML::Value << p.start_time;
  out << YAML::Key << "queries_succeeded" << YAML::Value << p.queries_succeeded;
  out << YAML::Key << "queries_failed" << YAML::Value << p.queries_failed;
  out << YAML::Key << "waypoints_received" << YAML::Value << p.waypoints_received;
  out << YAML::Key << "waypoints_reached" << YAML::Value << p.waypoints_reached;
  out << YAML::Key << "waypoints_cancelled" << YAML::Value << p.waypoints_cancelled;
  out << YAML::Key << "recoveries" << YAML::Value << p.recoveries;
  out << YAML::Key << "query_recoveries" << YAML::Value << p.query_recoveries;
  out << YAML::Key << "next_query_id" << YAML::Value << p.next_query_id;
  out << YAML::Key << "next_command_id" << YAML::Value << p.next_command_id;
  if (p.mission_depth) out << YAML::Key << "mission_depth" << YAML::Value << *p.mission_depth;
  out << YAML::Key << "plan" << YAML::Value << YAML::Literal << toYaml(p.plan);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

MissionProgress parseProgress(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = config::loadYaml(yaml_text);  // refuses alias cycles and alias bombs
  } catch (const YAML::Exception& error) {
    throw MissionError(source + ": not YAML: " + error.what());
  }
  if (!root.IsMap()) throw MissionError(source + ": not a map of progress fields");
  const auto field = [&](const char* name) {
    const YAML::Node node = root[name];
    if (!node || !node.IsScalar()) throw MissionError(source + ": field '" + name + "' missing");
    return node;
  };
  const auto number = [&](const char* name, auto* value) {
    try {
      *value = field(name).template as<std::decay_t<decltype(*value)>>();
    } catch (const YAML::Exception&) {
      throw MissionError(source + ": field '" + name + "': not a number: " + field(name).Scalar());
    }
  };
  MissionProgress p;
  p.launch_id = field("launch_id").Scalar();
  p.mission_id = field("mission_id").Scalar();
  const std::optional<msg::MissionState> state = missionStateFromString(field("state").Scalar());
  if (!state) throw MissionError(source + ": field 'state': unknown " + field("state").Scalar());
  p.state = *state;
  number("query_index", &p.query_index);
  number("start_time", &p.start_time);
  number("queries_succeeded", &p.queries_succeeded);
  number("queries_failed", &p.queries_failed);
  number("waypoints_received", &p.waypoints_received);
  number("waypoints_reached", &p.waypoints_reached);
  number("waypoints_cancelled", &p.waypoints_cancelled);
  number("recoveries", &p.recoveries);
  number("query_recoveries", &p.query_recoveries);
  number("next_query_id", &p.next_query_id);
  number("next_command_id", &p.next_command_id);
  if (root["mission_depth"]) {
    double depth = 0.0;
    number("mission_depth", &depth);
    p.mission_depth = depth;
  }
  p.plan = parseMission(field("plan").Scalar(), source + ": plan");
  if (p.running() &&
      (p.query_index < 0 || p.query_index >= static_cast<int32_t>(p.plan.queries.size()))) {
    throw MissionError(source + ": field 'query_index': " + std::to_string(p.query_index) +
                       " is not one of the plan's " + std::to_string(p.plan.queries.size()) +
                       " queries");
  }
  return p;
}

std::optional<MissionProgress> readProgress(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) return std::nullopt;
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw MissionError(file.string() + ": cannot read");
  return parseProgress(text.str(), file.string());
}

void writeProgress(const std::filesystem::path& file, const MissionProgress& progress) {
  config::writeFileAtomically(file, toYaml(progress));
}

}  // namespace auv::mission
