#include "auv/bag/dds/player.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "auv/bag/dds/qos_metadata.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/all.h"  // msg::Clock and its type support

namespace auv::bag {

const config::OptionTable<PlayerOptions>& PlayerOptions::table() {
  using O = PlayerOptions;
  static const config::OptionTable<O> kTable = {
      {"input", &O::input, "the .mcap file to play"},
      {"topics", &O::topics, "topics to play; empty: every channel of the bag"},
      {"rate", &O::rate, "playback speed (2: twice as fast as recorded)", "",
       config::Range::closed(0.01, 1000)},
      {"loop", &O::loop, "start again at the end until stopped"},
      {"delay_s", &O::delay_s, "wait after creating the writers, for readers to match", "s",
       config::Range::closed(0, 3600)},
      {"wait_for_readers", &O::wait_for_readers,
       "start as soon as every writer has a matched reader (at most delay_s)"},
      {"start_offset_s", &O::start_offset_s, "skip this much of the bag's beginning", "s",
       config::Range::atLeast(0)},
      {"vendor",
       &O::vendor,
       "DDS vendor of the player; empty: AUV_DDS",
       "",
       {},
       {"", "cyclonedds", "fastdds"}},
      {"domain_id", &O::domain_id, "DDS domain; -1: AUV_DOMAIN_ID", "",
       config::Range::closed(-1, 232)},
      {"qos_overrides", &O::qos_overrides,
       "topic=profile: offer a named QoS profile instead of the recorded QoS"},
      {"clock_hz", &O::clock_hz,
       "publish clock with the bag's time at this rate (wall Hz) for use_sim_time nodes; 0: off",
       "Hz", config::Range::closed(0, 1000)}};
  return kTable;
}

void PlayerOptions::check() const {
  config::checkOptions(*this, table());
  if (input.empty()) throw std::invalid_argument("input: no file given");
  for (const auto& topic : topics) interfaces::toDdsTopicName(topic);
  for (const auto& entry : qos_overrides) {
    const size_t at = entry.find('=');
    if (at == std::string::npos)
      throw std::invalid_argument("qos_overrides: expected topic=profile, got '" + entry + "'");
    interfaces::toDdsTopicName(entry.substr(0, at));
    interfaces::qosProfileByName(entry.substr(at + 1));  // names the known profiles
  }
}

struct Player::Output {
  std::string topic;
  const msg::TypeSupport* type = nullptr;
  interfaces::QosProfile qos;
  std::unique_ptr<interfaces::SerializedWriter> writer;
};

namespace {

/// Why `channel` cannot be played by this build, or "" when it can.
std::string unplayable(const Channel& channel, const Schema* schema,
                       const msg::TypeSupport** type) {
  if (channel.message_encoding != "cdr")
    return "message encoding '" + channel.message_encoding + "', not cdr";
  if (!schema) return "no schema";
  try {
    *type = &interfaces::typeSupportByName(schema->name);
  } catch (const std::invalid_argument&) {
    return "type '" + schema->name + "' is not one of this build's messages";
  }
  if (schema->encoding == "omgidl" &&
      std::string(schema->data.begin(), schema->data.end()) != (*type)->omg_idl)
    return "its schema of " + schema->name +
           " differs from this build's (recorded by another version)";
  return "";
}

/// The bag's time as it plays, published on `clock` at a fixed wall rate by a thread of its
/// own: before the first message the start time, then the first message's log time plus the
/// wall time since, times the rate, held at the bag's end.
class ClockPublisher {
 public:
  ClockPublisher(interfaces::Participant& participant, double hz, double rate, uint64_t start_ns,
                 uint64_t end_ns)
      : writer_(participant.createWriter("clock", msg::makeTypeSupport<msg::Clock>(),
                                         interfaces::clockQos())),
        rate_(rate),
        end_ns_(end_ns),
        base_ns_(start_ns) {
    const auto period = std::chrono::duration<double>(1.0 / hz);
    thread_ = std::thread([this, period] {
      std::unique_lock<std::mutex> lock(mutex_);
      while (!done_) {
        publishNow();
        wake_.wait_for(lock, period, [this] { return done_; });
      }
    });
  }
  /// Publishes the time once more (the bag's end after a whole pass), then stops.
  ~ClockPublisher() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
    publishNow();  // the thread is gone: no lock needed
  }
  /// A pass starts: bag time `log_ns` is now.
  void startPass(uint64_t log_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    base_ns_ = log_ns;
    base_wall_ = std::chrono::steady_clock::now();
    running_ = true;
  }

 private:
  /// Under mutex_ (or with the thread gone).
  void publishNow() {
    msg::Clock clock;
    clock.sim_time(interfaces::toMsgTime(static_cast<int64_t>(nowLocked())));
    writer_->write(&clock);
  }
  uint64_t nowLocked() const {
    if (!running_) return base_ns_;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - base_wall_).count();
    return std::min(end_ns_, base_ns_ + static_cast<uint64_t>(elapsed * rate_ * 1e9));
  }

  std::unique_ptr<interfaces::DataWriter> writer_;
  const double rate_;
  const uint64_t end_ns_;
  std::mutex mutex_;
  std::condition_variable wake_;
  uint64_t base_ns_;
  std::chrono::steady_clock::time_point base_wall_;
  bool running_ = false, done_ = false;
  std::thread thread_;
};

}  // namespace

Player::Player(PlayerOptions options) : options_(std::move(options)) {
  options_.check();
  reader_.open(options_.input);
  std::set<std::string> wanted;
  for (const auto& topic : options_.topics) wanted.insert("/" + interfaces::toDdsTopicName(topic));
  std::map<std::string, std::string> overrides;  // topic -> profile
  for (const auto& entry : options_.qos_overrides) {
    const size_t at = entry.find('=');
    overrides["/" + interfaces::toDdsTopicName(entry.substr(0, at))] = entry.substr(at + 1);
  }
  std::set<std::string> found;
  for (const auto& [id, channel] : reader_.channels()) {
    const std::string topic = "/" + interfaces::toDdsTopicName(channel.topic);
    if (!wanted.empty() && !wanted.count(topic)) continue;
    found.insert(topic);
    const auto schema = reader_.schemas().find(channel.schema_id);
    const msg::TypeSupport* type = nullptr;
    const std::string why =
        unplayable(channel, schema == reader_.schemas().end() ? nullptr : &schema->second, &type);
    if (!why.empty()) {
      if (!wanted.empty())
        throw std::invalid_argument(options_.input + ": topic " + topic +
                                    " cannot be played: " + why);
      skipped_.push_back(topic + ": " + why);
      continue;
    }
    auto output = std::make_unique<Output>();
    output->topic = topic;
    output->type = type;
    interfaces::QosProfile fallback = interfaces::commandQos();
    fallback.name = "recorded";
    try {
      output->qos = qosFromMetadata(channel.metadata, fallback);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(options_.input + ": topic " + topic + ": " + e.what());
    }
    if (overrides.count(topic)) output->qos = interfaces::qosProfileByName(overrides[topic]);
    outputs_[id] = std::move(output);
  }
  for (const auto& override_entry : overrides) {
    const std::string& topic = override_entry.first;  // a lambda may not capture a binding (C++17)
    if (!outputs_.empty() && std::none_of(outputs_.begin(), outputs_.end(),
                                          [&](const auto& o) { return o.second->topic == topic; }))
      throw std::invalid_argument("qos_overrides: no channel '" + topic + "' is played from " +
                                  options_.input);
  }
  for (const auto& topic : wanted) {
    if (!found.count(topic))
      throw std::invalid_argument(options_.input + ": no channel '" + topic +
                                  "' in the bag (auv bag info lists them)");
  }
  if (options_.clock_hz > 0 && std::any_of(outputs_.begin(), outputs_.end(), [](const auto& o) {
        return o.second->topic == "/clock";
      }))
    throw std::invalid_argument(options_.input +
                                ": clock_hz: the bag holds a recorded /clock; play it or leave it "
                                "out with a topic filter, not both");
}

Player::~Player() = default;

std::vector<std::string> Player::playing() const {
  std::vector<std::string> lines;
  for (const auto& [id, output] : outputs_)
    lines.push_back(output->topic + " [" + output->type->name + "] " + output->qos.summary());
  return lines;
}

PlayStats Player::play(const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  const auto wall_start = Clock::now();
  PlayStats stats;
  const interfaces::Vendor vendor = options_.vendor.empty()
                                        ? interfaces::vendorFromEnvironment()
                                        : interfaces::vendorFromString(options_.vendor);
  const int domain =
      options_.domain_id >= 0 ? options_.domain_id : interfaces::domainFromEnvironment();
  auto participant = interfaces::createParticipant(vendor, {domain, "auv_bag_play"});
  for (auto& [id, output] : outputs_)
    output->writer = participant->createSerializedWriter(output->topic, *output->type, output->qos);

  ReadFilter filter;
  for (const auto& [id, output] : outputs_)
    filter.topics.push_back(reader_.channels().at(id).topic);
  const uint64_t bag_start = reader_.statistics().message_start_time;
  filter.start_ns = bag_start + static_cast<uint64_t>(options_.start_offset_s * 1e9);
  // From the start: nodes with use_sim_time have a time while readers match.
  std::unique_ptr<ClockPublisher> clock;
  if (options_.clock_hz > 0)
    clock =
        std::make_unique<ClockPublisher>(*participant, options_.clock_hz, options_.rate,
                                         filter.start_ns, reader_.statistics().message_end_time);

  const auto sleep_until = [&](Clock::time_point when) {
    while (!stop && Clock::now() < when)
      std::this_thread::sleep_for(
          std::min<Clock::duration>(when - Clock::now(), std::chrono::milliseconds(50)));
  };
  const auto delay_end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(options_.delay_s));
  if (options_.wait_for_readers) {
    const auto all_matched = [&] {
      for (const auto& [id, output] : outputs_)
        if (output->writer->matchedReaders() == 0) return false;
      return true;
    };
    while (!stop && !all_matched() && Clock::now() < delay_end)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  } else {
    sleep_until(delay_end);
  }

  while (!stop && !outputs_.empty()) {
    auto messages = reader_.messages(filter);
    std::optional<uint64_t> first_log;
    Clock::time_point pass_start;
    while (!stop) {
      auto message = messages.next();
      if (!message) break;
      const auto output = outputs_.find(message->message.channel_id);
      if (output == outputs_.end()) continue;
      if (!first_log) {
        first_log = message->message.log_time;
        pass_start = Clock::now();
        if (clock) clock->startPass(*first_log);
      }
      // Log times of one recording are in order; a message logged before the first (clocks
      // of several publishers) goes out at once.
      const double offset_s =
          message->message.log_time > *first_log
              ? static_cast<double>(message->message.log_time - *first_log) * 1e-9 / options_.rate
              : 0.0;
      sleep_until(pass_start + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(offset_s)));
      if (stop) break;
      try {
        output->second->writer->write(message->message.data);
      } catch (const std::invalid_argument&) {
        ++stats.refused;
        continue;
      }
      ++stats.messages;
      ++stats.per_topic[output->second->topic];
    }
    if (stop) break;
    ++stats.loops;
    if (!options_.loop) break;
  }
  stats.stopped = stop;
  for (auto& [id, output] : outputs_) {
    if (output->qos.reliability == interfaces::Reliability::RELIABLE)
      output->writer->waitForAcknowledgments(5.0);
  }
  stats.wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  return stats;
}

}  // namespace auv::bag
