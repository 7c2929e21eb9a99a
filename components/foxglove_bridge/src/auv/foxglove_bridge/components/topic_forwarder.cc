#include "auv/foxglove_bridge/components/topic_forwarder.h"

#include <algorithm>
#include <chrono>

#include "auv/foxglove_bridge/scene.h"

namespace auv::foxglove_bridge {
namespace {

constexpr const char* kCompressedImageType = "auv::msg::CompressedImage";

std::string rosName(const std::string& topic) { return "/" + interfaces::toDdsTopicName(topic); }

}  // namespace

TopicForwarder::TopicForwarder(interfaces::Vendor vendor, int domain_id, ForwarderOptions options,
                               BridgeCore& core)
    : vendor_(vendor), domain_id_(domain_id), options_(std::move(options)), core_(core) {
  for (auto& topic : options_.topics) topic = rosName(topic);
  for (auto& topic : options_.exclude) topic = rosName(topic);
  // Serialized endpoints need a participant of their own (serialized.h).
  participant_ = interfaces::createParticipant(vendor_, {domain_id_, "_auv_foxglove_bridge"});
  inspector_ = std::make_unique<interfaces::GraphInspector>(vendor_, domain_id_);
}

TopicForwarder::~TopicForwarder() { stop(); }

void TopicForwarder::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] { loop(); });
}

void TopicForwarder::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  std::map<std::string, std::unique_ptr<Topic>> topics;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    topics.swap(topics_);
  }
  for (auto& entry : topics) entry.second->reader.reset();  // waits for running callbacks
}

void TopicForwarder::loop() {
  const auto period = std::chrono::milliseconds(
      std::max<int64_t>(10, static_cast<int64_t>(options_.discovery_period * 1000)));
  while (running_) {
    discoverNow();
    // Wakes on discovery events, so a new topic is advertised within ~period.
    inspector_->waitFor([](const interfaces::GraphSnapshot&) { return false; }, period);
  }
}

bool TopicForwarder::wanted(const std::string& topic) const {
  const auto has = [&](const std::vector<std::string>& list) {
    return std::find(list.begin(), list.end(), topic) != list.end();
  };
  return (options_.topics.empty() || has(options_.topics)) && !has(options_.exclude);
}

void TopicForwarder::discoverNow() {
  const interfaces::GraphSnapshot graph = inspector_->snapshot();
  const auto types = graph.topicTypes();
  // Gone: no writer left, or announced with another type now.
  std::vector<std::unique_ptr<Topic>> gone;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = topics_.begin(); it != topics_.end();) {
      const auto t = types.find(it->first);
      const bool alive = t != types.end() && t->second.size() == 1 &&
                         *t->second.begin() == it->second->type->name &&
                         !graph.endpointsOn(it->first, true).empty();
      if (alive) {
        ++it;
      } else {
        gone.push_back(std::move(it->second));
        it = topics_.erase(it);
      }
    }
  }
  for (auto& topic : gone) {
    core_.removeChannel(topic->channel);
    if (topic->camera_channel) core_.removeChannel(topic->camera_channel);
    topic->reader.reset();
  }
  for (const auto& [name, type_names] : types) {
    if (!wanted(name)) continue;
    const auto writers = graph.endpointsOn(name, true);
    if (writers.empty()) continue;  // readers only: nothing to forward yet
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (topics_.count(name)) continue;
      if (type_names.size() > 1) {
        skipped_[name] = "announced with " + std::to_string(type_names.size()) + " types";
        continue;
      }
      const msg::TypeSupport* type = msg::findType(*type_names.begin());
      if (type == nullptr) {
        skipped_[name] = "type '" + *type_names.begin() + "' is not one of auv-inspect's messages";
        continue;
      }
      skipped_.erase(name);
      auto topic = std::make_unique<Topic>();
      topic->name = name;
      topic->type = type;
      topic->qos = interfaces::compatibleReaderQos(writers, options_.reader_depth);
      topic->droppable = topic->qos.reliability != interfaces::Reliability::RELIABLE;
      topics_[name] = std::move(topic);
    }
    // Channels are advertised outside the lock: a subscription may come back at once.
    const msg::TypeSupport* type = msg::findType(*type_names.begin());
    const uint32_t channel =
        core_.addChannel({0, name, "cdr", type->name, type->omg_idl, "omgidl"});
    uint32_t camera = 0;
    if (type->name == kCompressedImageType)
      camera = core_.addChannel({0, cameraChannel(name), "json", kCompressedImage,
                                 jsonSchema(kCompressedImage), "jsonschema"});
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = topics_.find(name);
      if (it != topics_.end()) {
        it->second->channel = channel;
        it->second->camera_channel = camera;
      }
    }
    reconcile(channel);
  }
}

bool TopicForwarder::reconcile(uint32_t channel) {
  std::unique_ptr<interfaces::SerializedReader> dropped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Topic* topic = nullptr;
    for (auto& entry : topics_) {
      if (channel != 0 &&
          (entry.second->channel == channel || entry.second->camera_channel == channel))
        topic = entry.second.get();
    }
    if (topic == nullptr) return false;
    const bool want = (topic->channel && core_.hasSubscribers(topic->channel)) ||
                      (topic->camera_channel && core_.hasSubscribers(topic->camera_channel));
    if (want && !topic->reader) {
      topic->reader = participant_->createSerializedReader(
          topic->name, *topic->type, topic->qos,
          [this, topic](interfaces::SerializedReader& r) { onSamples(*topic, r); });
    } else if (!want && topic->reader) {
      dropped = std::move(topic->reader);
    }
  }
  dropped.reset();  // waits for a running callback, which never takes mutex_
  return true;
}

void TopicForwarder::onSamples(Topic& topic, interfaces::SerializedReader& reader) {
  // A middleware thread: everything below only queues (never waits for a socket).
  while (reader.take(topic.sample)) {
    const auto& s = topic.sample;
    const auto stamp = static_cast<uint64_t>(s.reception_timestamp_ns);
    if (core_.publish(topic.channel, stamp, s.cdr.data(), s.cdr.size(), topic.droppable))
      ++forwarded_;
    if (topic.camera_channel && core_.hasSubscribers(topic.camera_channel)) {
      static const auto& image_type = interfaces::typeSupportByName(kCompressedImageType);
      msg::CompressedImage image;
      if (!interfaces::decodeSerialized(image_type, s.cdr, &image)) continue;
      const std::string text = compressedImage(image).dump();
      core_.publish(topic.camera_channel, stamp, reinterpret_cast<const uint8_t*>(text.data()),
                    text.size(), true);
    }
  }
}

size_t TopicForwarder::activeReaders() const {
  std::lock_guard<std::mutex> lock(mutex_);
  size_t count = 0;
  for (const auto& entry : topics_) count += entry.second->reader ? 1 : 0;
  return count;
}

std::vector<std::string> TopicForwarder::skipped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> list;
  for (const auto& [topic, why] : skipped_) list.push_back(topic + ": " + why);
  return list;
}

}  // namespace auv::foxglove_bridge
