#include "auv/foxglove_bridge/components/foxglove_bridge_component.h"

#include <fstream>
#include <sstream>

#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/option_parameters.h"

namespace auv::foxglove_bridge {
namespace {

using nlohmann::json;
constexpr uint32_t kStartService = 1;
constexpr uint32_t kAbortService = 2;

json parameterJson(const interfaces::ParameterValue& value) {
  return std::visit([](const auto& v) { return json(v); }, value);
}

ServiceDescription service(uint32_t id, const std::string& name, const msg::TypeSupport& request,
                           const msg::TypeSupport& reply) {
  // JSON in and out: the request's fields by name (the header is the bridge's), as the
  // schema's description says; the OMG IDL travels along for reference.
  ServiceDescription s;
  s.id = id;
  s.name = name;
  s.type = request.name;
  s.request_schema_name = request.name;
  s.response_schema_name = reply.name;
  s.request_schema =
      json{{"type", "object"},
           {"description", std::string("fields of ") + request.name +
                               " (header filled by the bridge):\n" + request.omg_idl}}
          .dump();
  s.response_schema =
      json{{"type", "object"}, {"description", std::string("fields of ") + reply.name}}.dump();
  return s;
}

}  // namespace

json yamlToJson(const YAML::Node& node) {
  if (node.IsMap()) {
    json object = json::object();
    for (const auto& entry : node) object[entry.first.Scalar()] = yamlToJson(entry.second);
    return object;
  }
  if (node.IsSequence()) {
    json array = json::array();
    for (const auto& element : node) array.push_back(yamlToJson(element));
    return array;
  }
  if (!node.IsScalar()) return nullptr;
  const std::string& text = node.Scalar();
  if (text == "true" || text == "false") return text == "true";
  // A number only if JSON reads the whole scalar as one ("007" and "1e" stay text).
  const json number = json::parse(text, nullptr, false);
  if (number.is_number() && number.dump() == text) return number;
  if (number.is_number_float()) return number;
  return text;
}

YAML::Node overlayJson(const YAML::Node& defaults, const json& value, const std::string& path) {
  if (value.is_object()) {
    if (!defaults.IsMap())
      throw std::invalid_argument((path.empty() ? "request" : path) + ": not a struct");
    YAML::Node out = YAML::Clone(defaults);
    for (const auto& [key, field] : value.items()) {
      const std::string where = path.empty() ? key : path + "." + key;
      if (!defaults[key]) throw std::invalid_argument(where + ": no such field");
      out[key] = overlayJson(defaults[key], field, where);
    }
    return out;
  }
  // Anything else is read by the type's own from_yaml, which names a bad value.
  return YAML::Load(value.dump());
}

const config::OptionTable<FoxgloveBridgeComponent::Options>&
FoxgloveBridgeComponent::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"address", &O::address, "IP address to listen on; 127.0.0.1 keeps it on this machine"},
      {"port", &O::port, "TCP port of the WebSocket server; 0: any free port", "",
       Range::closed(0, 65535)},
      {"send_buffer_limit", &O::send_buffer_limit,
       "bytes queued per client beyond which its best-effort samples are dropped (4x: the "
       "client is disconnected)",
       "B", Range::closed(1024, 4e9)},
      {"token", &O::token, "access token clients must give as ?token=...; empty: none"},
      {"token_file", &O::token_file, "file holding the access token (first line); overrides token"},
      {"services", &O::services, "offer mission/start and mission/abort to clients"},
      {"parameters", &O::parameters, "let clients read the bridge's parameters"},
      {"service_timeout", &O::service_timeout, "how long a service call waits for its reply", "s",
       Range::closed(0.1, 600)},
      {"topics", &O::topics, "DDS topics forwarded; empty: every topic"},
      {"exclude", &O::exclude, "DDS topics never forwarded"},
      {"discovery_period", &O::discovery_period, "longest wait between looks at the DDS graph", "s",
       Range::closed(0.01, 60)},
      {"odometry_topic", &O::odometry_topic, "estimated pose: /tf and trajectory_estimated"},
      {"ground_truth_topic", &O::ground_truth_topic, "true pose: trajectory_true"},
      {"map_topic", &O::map_topic, "OctomapUpdate topic drawn on /foxglove/map"},
      {"map_id", &O::map_id, "which map of map_topic"},
      {"tree_topic", &O::tree_topic, "PlannerTree topic drawn on /foxglove/planner"},
      {"path_topic", &O::path_topic, "Path topic drawn on /foxglove/planner"},
      {"map_period", &O::map_period, "shortest time between two map scenes", "s",
       Range::closed(0.05, 600)},
      {"tree_period", &O::tree_period,
       "shortest time between two planner trees on /foxglove/planner (a tree of 10^4 nodes is "
       "~0.5 MB of JSON)",
       "s", Range::closed(0.05, 600)},
      {"map_show_free", &O::map_show_free, "draw free leaves too (faint green)"},
      {"map_show_unknown", &O::map_show_unknown,
       "draw unknown cells inside the map's extent too (faint grey)"},
      {"map_max_cubes", &O::map_max_cubes, "cubes per map scene at most (occupied first)", "",
       Range::closed(1, 1e7)},
      {"vehicle_period", &O::vehicle_period, "period of /foxglove/vehicle", "s",
       Range::closed(0.01, 60)},
      {"trajectory_min_step", &O::trajectory_min_step,
       "a trajectory point closer than this to the last is not kept", "m", Range::closed(0, 100)},
      {"trajectory_max_points", &O::trajectory_max_points,
       "points per trajectory at most (the oldest go)", "", Range::closed(2, 1e7)},
      {"vehicle_length", &O::vehicle_length, "length of the vehicle's box", "m", Range::above(0)},
      {"vehicle_width", &O::vehicle_width, "width and height of the vehicle's box", "m",
       Range::above(0)},
  };
  return kTable;
}

void FoxgloveBridgeComponent::Options::check() const {
  config::checkOptions(*this, table(), "parameter ");
  for (const auto* name :
       {&odometry_topic, &ground_truth_topic, &map_topic, &tree_topic, &path_topic}) {
    try {
      interfaces::toDdsTopicName(*name);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("parameter topic: ") + e.what());
    }
  }
}

FoxgloveBridgeComponent::~FoxgloveBridgeComponent() { cleanup(); }

void FoxgloveBridgeComponent::configure(interfaces::Node& node) {
  node_ = &node;
  interfaces::declareOptions(node.parameters(), "", Options::table(), options_, true);
  options_.check();
  Options& o = options_;
  if (!o.token_file.empty()) {
    std::ifstream in(o.token_file);
    if (!in || !std::getline(in, o.token) || o.token.empty())
      throw std::invalid_argument("parameter token_file: cannot read a token from '" +
                                  o.token_file + "'");
  }
  ServerOptions server;
  server.address = o.address;
  server.port = static_cast<uint16_t>(o.port);
  server.send_buffer_limit = static_cast<size_t>(o.send_buffer_limit);
  server.token = o.token;
  server_ = std::make_unique<WebSocketServer>(server);
  CoreOptions core;
  core.services = o.services;
  core.parameters = o.parameters;
  core.metadata = {{"vendor", interfaces::toString(node.vendor())},
                   {"domain_id", std::to_string(node.domainId())}};
  core_ = std::make_unique<BridgeCore>(core, *server_, static_cast<Listener&>(*this));
  ForwarderOptions forwarder{o.topics, o.exclude, o.discovery_period, 100};
  forwarder_ = std::make_unique<TopicForwarder>(node.vendor(), node.domainId(), forwarder, *core_);
  if (o.services) {
    start_ = node.createClient<msg::StartMissionRequest, msg::StartMissionReply>("mission/start");
    abort_ = node.createClient<msg::TriggerRequest, msg::TriggerReply>("mission/abort");
    core_->setServices(
        {service(kStartService, "mission/start", msg::makeTypeSupport<msg::StartMissionRequest>(),
                 msg::makeTypeSupport<msg::StartMissionReply>()),
         service(kAbortService, "mission/abort", msg::makeTypeSupport<msg::TriggerRequest>(),
                 msg::makeTypeSupport<msg::TriggerReply>())});
  }
  createVisuals();
}

void FoxgloveBridgeComponent::createVisuals() {
  interfaces::Node& node = *node_;
  const Options& o = options_;
  const auto channel = [&](const char* topic, const char* schema) {
    return core_->addChannel({0, topic, "json", schema, jsonSchema(schema), "jsonschema"});
  };
  map_channel_ = channel(kMapChannel, kSceneUpdate);
  planner_channel_ = channel(kPlannerChannel, kSceneUpdate);
  vehicle_channel_ = channel(kVehicleChannel, kSceneUpdate);
  tf_channel_ = channel(kTfChannel, kFrameTransform);
  estimated_ = std::make_unique<Trajectory>(o.trajectory_min_step, o.trajectory_max_points);
  truth_ = std::make_unique<Trajectory>(o.trajectory_min_step, o.trajectory_max_points);
  subscriptions_.push_back(node.createSubscription<msg::Odometry>(
      o.odometry_topic, interfaces::stateQos(), [this](const msg::Odometry& m) {
        const auto& p = m.pose().pose().position();
        estimated_->add(p.x(), p.y(), p.z());
        const int64_t stamp = interfaces::toNanoseconds(m.header().stamp());
        if (core_->hasSubscribers(tf_channel_))
          publishJson(tf_channel_, vehicleTransform(m), stamp);
        last_odometry_ns_ = stamp;
      }));
  subscriptions_.push_back(node.createSubscription<msg::Odometry>(
      o.ground_truth_topic, interfaces::stateQos(), [this](const msg::Odometry& m) {
        const auto& p = m.pose().pose().position();
        truth_->add(p.x(), p.y(), p.z());
      }));
  subscriptions_.push_back(node.createSubscription<msg::OctomapUpdate>(
      o.map_topic, interfaces::mapQos(), [this](const msg::OctomapUpdate& m) {
        if (!map_) map_ = std::make_unique<mapping::MapReplica>(options_.map_id, m.resolution());
        const auto outcome = map_->apply(m);
        if (outcome == mapping::MapReplica::Outcome::APPLIED) map_dirty_ = true;
        if (outcome == mapping::MapReplica::Outcome::REJECTED)
          AUV_WARN(node_->logger(), "map update refused: " << map_->error());
      }));
  subscriptions_.push_back(node.createSubscription<msg::PlannerTree>(
      o.tree_topic, interfaces::viewingQos(), [this](const msg::PlannerTree& m) {
        last_tree_ = std::make_shared<msg::PlannerTree>(m);
        tree_dirty_ = true;  // drawn by tree_timer_: trees come faster than a client needs
      }));
  subscriptions_.push_back(node.createSubscription<msg::Path>(
      o.path_topic, interfaces::viewingQos(), [this](const msg::Path& m) {
        last_path_ = std::make_shared<msg::Path>(m);
        if (core_->hasSubscribers(planner_channel_))
          publishJson(planner_channel_, pathScene(m),
                      interfaces::toNanoseconds(m.header().stamp()));
      }));
  map_timer_ = node.createTimer(o.map_period, [this] { publishMap(false); });
  tree_timer_ = node.createTimer(o.tree_period, [this] {
    if (!tree_dirty_ || !last_tree_ || !core_->hasSubscribers(planner_channel_)) return;
    tree_dirty_ = false;
    publishJson(planner_channel_, treeScene(*last_tree_),
                interfaces::toNanoseconds(last_tree_->header().stamp()));
  });
  vehicle_timer_ = node.createTimer(o.vehicle_period, [this] {
    publishVehicle();
    // A new subscriber of the planner gets the last tree and path at once.
    if (resend_planner_.exchange(false)) {
      if (last_tree_) publishJson(planner_channel_, treeScene(*last_tree_), 0);
      if (last_path_) publishJson(planner_channel_, pathScene(*last_path_), 0);
    }
    if (resend_map_.exchange(false)) publishMap(true);
  });
}

void FoxgloveBridgeComponent::publishJson(uint32_t channel, const json& message, int64_t stamp_ns) {
  const std::string text = message.dump(-1, ' ', false, json::error_handler_t::replace);
  const int64_t stamp = stamp_ns > 0 ? stamp_ns : node_->clock().nowNs();
  core_->publish(channel, static_cast<uint64_t>(stamp),
                 reinterpret_cast<const uint8_t*>(text.data()), text.size(), true);
}

void FoxgloveBridgeComponent::publishMap(bool force) {
  if (!map_ || !core_->hasSubscribers(map_channel_) || (!map_dirty_ && !force)) return;
  MapStyle style{options_.map_show_free, options_.map_show_unknown,
                 static_cast<size_t>(options_.map_max_cubes)};
  const int64_t stamp = node_->clock().nowNs();
  publishJson(map_channel_, mapScene(map_->tree(), style, stamp), stamp);
  map_dirty_ = false;
}

void FoxgloveBridgeComponent::publishVehicle() {
  const int64_t stamp = last_odometry_ns_ > 0 ? last_odometry_ns_ : node_->clock().nowNs();
  // Static, but the protocol has no latching: again every period, for clients that come later.
  if (core_->hasSubscribers(tf_channel_))
    publishJson(tf_channel_, displayFrameTransform(stamp), stamp);
  if (!core_->hasSubscribers(vehicle_channel_)) return;
  publishJson(
      vehicle_channel_,
      vehicleScene(*estimated_, *truth_, stamp, options_.vehicle_length, options_.vehicle_width),
      stamp);
}

void FoxgloveBridgeComponent::activate() {
  server_->start(*core_);
  forwarder_->start();
  if (options_.services) {
    std::lock_guard<std::mutex> lock(calls_mutex_);
    calls_stop_ = false;
    service_thread_ = std::thread([this] { serviceLoop(); });
  }
  AUV_INFO(node_->logger(), "Foxglove WebSocket server on ws://"
                                << options_.address << ":" << server_->port()
                                << (options_.token.empty() ? "" : " (token required)")
                                << (options_.services ? ", services offered" : "")
                                << (options_.parameters ? ", parameters offered" : ""));
  if (options_.address != "127.0.0.1" && options_.address != "::1" && options_.token.empty())
    AUV_WARN(node_->logger(), "listening on " << options_.address
                                              << " without a token: anyone who reaches the port "
                                                 "reads every topic, outside DDS Security");
}

void FoxgloveBridgeComponent::deactivate() {
  if (server_) server_->stop();
  if (forwarder_) forwarder_->stop();
  {
    std::lock_guard<std::mutex> lock(calls_mutex_);
    calls_stop_ = true;
  }
  calls_wake_.notify_all();
  if (service_thread_.joinable()) service_thread_.join();
}

void FoxgloveBridgeComponent::cleanup() {
  deactivate();
  map_timer_.reset();
  vehicle_timer_.reset();
  tree_timer_.reset();
  subscriptions_.clear();
  forwarder_.reset();
  start_.reset();
  abort_.reset();
  // server_ and core_ stay until destruction: tests read their counters after a stop.
}

void FoxgloveBridgeComponent::channelSubscribed(uint32_t channel) {
  if (channel == map_channel_) resend_map_ = true;
  if (channel == planner_channel_) resend_planner_ = true;
  if (forwarder_) forwarder_->reconcile(channel);
}

void FoxgloveBridgeComponent::channelUnsubscribed(uint32_t channel) {
  if (forwarder_) forwarder_->reconcile(channel);
}

void FoxgloveBridgeComponent::callService(ClientId client, const ServiceCallRequest& request) {
  {
    std::lock_guard<std::mutex> lock(calls_mutex_);
    calls_.emplace_back(client, request);
  }
  calls_wake_.notify_all();
}

void FoxgloveBridgeComponent::serviceLoop() {
  std::unique_lock<std::mutex> lock(calls_mutex_);
  while (true) {
    calls_wake_.wait(lock, [this] { return calls_stop_ || !calls_.empty(); });
    if (calls_stop_) return;
    auto [client, request] = calls_.front();
    calls_.pop_front();
    lock.unlock();
    try {
      core_->serviceResponse(client, request, runService(request));
    } catch (const std::exception& e) {
      core_->serviceFailure(client, request, e.what());
    }
    lock.lock();
  }
}

std::string FoxgloveBridgeComponent::runService(const ServiceCallRequest& request) {
  const json body =
      request.payload.empty() ? json::object() : json::parse(request.payload, nullptr, false);
  if (body.is_discarded() || !body.is_object())
    throw std::invalid_argument("request: expected a JSON object of the request's fields");
  const auto timeout =
      std::chrono::milliseconds(static_cast<int64_t>(options_.service_timeout * 1000));
  const auto call = [&](auto& client, auto req, auto rep) -> std::string {
    using Req = decltype(req);
    const auto type = msg::makeTypeSupport<Req>();
    YAML::Node fields = overlayJson(type.to_yaml(&req), body);
    type.from_yaml(fields, &req);  // names a bad value
    const auto status = client->call(req, &rep, timeout);
    if (status == interfaces::CallStatus::NO_SERVICE)
      throw std::runtime_error(client->name() + ": no service (is the mission handler running?)");
    if (status == interfaces::CallStatus::TIMEOUT)
      throw std::runtime_error(client->name() + ": no reply within service_timeout");
    const auto reply_type = msg::makeTypeSupport<decltype(rep)>();
    return yamlToJson(reply_type.to_yaml(&rep))
        .dump(-1, ' ', false, json::error_handler_t::replace);
  };
  if (request.service_id == kStartService)
    return call(start_, msg::StartMissionRequest{}, msg::StartMissionReply{});
  return call(abort_, msg::TriggerRequest{}, msg::TriggerReply{});
}

json FoxgloveBridgeComponent::getParameters(const std::vector<std::string>& names) {
  json list = json::array();
  auto& p = node_->parameters();
  for (const std::string& name : names.empty() ? p.names() : names) {
    if (!p.has(name)) throw std::invalid_argument("no parameter '" + name + "'");
    list.push_back({{"name", name}, {"value", parameterJson(p.getValue(name))}});
  }
  return list;
}

void FoxgloveBridgeComponent::setParameters(const SetParameters& request) {
  for (const auto& [name, value] : request.parameters) {
    const auto result = node_->parameters().setFromYaml(name, value.dump());
    if (!result.ok) throw std::invalid_argument(result.reason);
  }
}

}  // namespace auv::foxglove_bridge

AUV_REGISTER_COMPONENT(auv::foxglove_bridge::FoxgloveBridgeComponent, "foxglove_bridge",
                       "Foxglove WebSocket server: every DDS topic, the map, planner and vehicle")
