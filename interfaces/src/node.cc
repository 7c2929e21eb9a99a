#include "auv/interfaces/node.h"
#include "auv/interfaces/msg_time.h"

#include <algorithm>
#include <chrono>

namespace auv::interfaces {
namespace {

msg::LogLevel toMsgLevel(LogLevel level) {
  switch (level) {
    case LogLevel::DEBUG:
      return msg::LOG_LEVEL_DEBUG;
    case LogLevel::INFO:
      return msg::LOG_LEVEL_INFO;
    case LogLevel::WARN:
      return msg::LOG_LEVEL_WARN;
    case LogLevel::ERROR:
      return msg::LOG_LEVEL_ERROR;
    case LogLevel::FATAL:
      return msg::LOG_LEVEL_FATAL;
  }
  return msg::LOG_LEVEL_UNSET;
}

// `log` keeps each node's recent lines for late joiners (keyed by node name).
QosProfile logQos() {
  QosProfile q = latchedStateQos();
  q.name = "log";
  q.depth = 20;
  return q;
}

}  // namespace

Node::Node(const std::string& name, const NodeOptions& options)
    : name_(name), logger_(name), waker_(std::make_shared<Waker>()) {
  if (name.empty()) throw std::invalid_argument("node name must not be empty");
  parameters_ = std::make_unique<Parameters>(name);
  for (const auto& file : options.params_files) parameters_->loadFile(file);
  for (const auto& assignment : options.overrides)
    parameters_->setOverride(assignment, kCommandLineSource);

  const bool use_sim_time = parameters_->declare<bool>(
      "use_sim_time", false,
      {"follow the simulation clock on the `clock` topic", "", {}, {}, {}, true});
  const std::string level =
      parameters_->declare<std::string>("log_level", "info",
                                        {"lowest level printed and published on `log`",
                                         "",
                                         {},
                                         {},
                                         {"debug", "info", "warn", "error", "fatal"}});
  logger_.setLevel(logLevelFromString(level));
  clock_ =
      std::make_unique<Clock>(use_sim_time ? Clock::Source::SIMULATION : Clock::Source::SYSTEM);

  domain_id_ = options.domain_id ? *options.domain_id : domainFromEnvironment();
  const Vendor vendor = options.vendor ? *options.vendor : vendorFromEnvironment();
  participant_ = createParticipant(vendor, {domain_id_, name});

  static const msg::TypeSupport log_type = msg::makeTypeSupport<msg::LogEntry>();
  log_writer_ = participant_->createWriter("log", log_type, logQos());
  logger_.setSink([this](LogLevel lvl, const std::string& text) {
    msg::LogEntry entry;
    entry.stamp(toMsgTime(clock_->nowNs()));
    entry.level(toMsgLevel(lvl));
    entry.node_name(name_);
    entry.message(text);
    try {
      log_writer_->write(&entry);
    } catch (...) {
      // Logging must never take a component down; stderr already has the line.
    }
  });

  if (use_sim_time) {
    static const msg::TypeSupport clock_type = msg::makeTypeSupport<msg::Clock>();
    // Taken in the DDS thread so time advances even while a callback runs.
    clock_reader_ =
        participant_->createReader("clock", clock_type, clockQos(), [this](DataReader& reader) {
          msg::Clock sample;
          bool advanced = false;
          while (reader.take(&sample, nullptr)) {
            clock_->setSimulationTime(toNanoseconds(sample.sim_time()));
            advanced = true;
          }
          if (advanced) waker_->notify();
        });
  }
}

Node::~Node() {
  logger_.setSink(nullptr);
  clock_reader_.reset();
  log_writer_.reset();
}

QosProfile Node::resolveQos(const std::string& topic, const QosProfile& qos) {
  const std::string name = "qos." + toDdsTopicName(topic);
  if (parameters_->has(name)) return qosProfileByName(parameters_->get<std::string>(name));
  std::vector<std::string> choices = qosProfileNames();
  if (std::find(choices.begin(), choices.end(), qos.name) == choices.end())
    choices.push_back(qos.name);
  const std::string chosen = parameters_->declare<std::string>(
      name, qos.name, {"QoS profile of topic " + topic, "", {}, {}, choices, true});
  if (chosen == qos.name) return qos;
  return qosProfileByName(chosen);
}

std::shared_ptr<Timer> Node::createTimer(double period_s, std::function<void()> callback) {
  if (!(period_s > 0))
    throw std::invalid_argument("timer period must be > 0 s, got " + std::to_string(period_s));
  auto timer =
      std::make_shared<Timer>(*clock_, static_cast<int64_t>(period_s * 1e9), std::move(callback));
  addWaitable(timer);
  waker_->notify();
  return timer;
}

void Node::addWaitable(const std::shared_ptr<Waitable>& waitable) {
  std::lock_guard<std::mutex> lock(mutex_);
  waitables_.push_back(waitable);
}

bool Node::executeReady() {
  std::vector<std::shared_ptr<Waitable>>& alive = execute_scratch_;  // no allocation per call
  {
    std::lock_guard<std::mutex> lock(mutex_);
    waitables_.erase(std::remove_if(waitables_.begin(), waitables_.end(),
                                    [](const auto& w) { return w.expired(); }),
                     waitables_.end());
    for (const auto& w : waitables_) alive.push_back(w.lock());
  }
  bool any = false;
  for (const auto& w : alive) {
    if (w) any = w->execute() || any;
  }
  alive.clear();  // keeps the capacity, drops the references
  return any;
}

std::optional<int64_t> Node::nanosecondsUntilNextTimer() const {
  std::optional<int64_t> earliest;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& weak : waitables_) {
    if (auto w = weak.lock()) {
      if (auto due = w->nanosecondsUntilDue())
        earliest = earliest ? std::min(*earliest, *due) : *due;
    }
  }
  return earliest;
}

}  // namespace auv::interfaces
