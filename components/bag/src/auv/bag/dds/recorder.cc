#include "auv/bag/dds/recorder.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "auv/bag/dds/qos_metadata.h"
#include "auv/interfaces/graph.h"
#include "auv/interfaces/serialized.h"

namespace auv::bag {

using interfaces::GraphSnapshot;
using interfaces::SerializedReader;
using interfaces::SerializedSample;

const config::OptionTable<RecorderOptions>& RecorderOptions::table() {
  using O = RecorderOptions;
  static const config::OptionTable<O> kTable = {
      {"output", &O::output, "the .mcap file to write"},
      {"topics", &O::topics, "topics to record; empty: every topic on the domain"},
      {"exclude", &O::exclude, "topics never recorded"},
      {"vendor",
       &O::vendor,
       "DDS vendor of the recorder; empty: AUV_DDS",
       "",
       {},
       {"", "cyclonedds", "fastdds"}},
      {"domain_id", &O::domain_id, "DDS domain; -1: AUV_DOMAIN_ID", "",
       config::Range::closed(-1, 232)},
      {"compression", &O::compression, "chunk compression", "", {}, {"none", "zstd", "lz4"}},
      {"chunk_size", &O::chunk_size, "messages after which a chunk is compressed and written",
       "bytes", config::Range::closed(1024, 256.0 * 1024 * 1024)},
      {"flush_period_s", &O::flush_period_s,
       "a chunk is written at least this often: what a crash of the recorder loses", "s",
       config::Range::closed(0.05, 3600)},
      {"reader_depth", &O::reader_depth, "keep-last depth of the readers: a burst they absorb",
       "samples", config::Range::closed(1, 100000)},
      {"overwrite", &O::overwrite, "replace an existing output file"}};
  return kTable;
}

void RecorderOptions::check() const {
  config::checkOptions(*this, table());
  if (output.empty()) throw std::invalid_argument("output: no file given");
  for (const auto& topic : topics) interfaces::toDdsTopicName(topic);  // names the bad one
  for (const auto& topic : exclude) interfaces::toDdsTopicName(topic);
}

namespace {

std::string rosName(const std::string& topic) { return "/" + interfaces::toDdsTopicName(topic); }

}  // namespace

struct Recorder::Topic {
  TopicStats stats;
  uint16_t channel = 0;
  uint32_t sequence = 0;
  std::map<interfaces::Guid, int64_t> last_sequence;  // per writer
  SerializedSample sample;
  std::unique_ptr<SerializedReader> reader;  // last member: destroyed first
};

Recorder::Recorder(RecorderOptions options) : options_(std::move(options)) {
  options_.check();
  for (auto& topic : options_.topics) topic = rosName(topic);
  for (auto& topic : options_.exclude) topic = rosName(topic);
  vendor_ = options_.vendor.empty() ? interfaces::vendorFromEnvironment()
                                    : interfaces::vendorFromString(options_.vendor);
  domain_id_ = options_.domain_id >= 0 ? options_.domain_id : interfaces::domainFromEnvironment();
  McapWriterOptions writer_options;
  writer_options.compression = options_.compression;
  writer_options.chunk_size = options_.chunk_size;
  writer_options.overwrite = options_.overwrite;
  writer_ = std::make_unique<McapWriter>(writer_options);
  writer_->open(options_.output);
}

Recorder::~Recorder() {
  try {
    stop();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag record: %s\n", e.what());
  }
}

void Recorder::start() {
  if (running_) return;
  participant_ = interfaces::createParticipant(vendor_, {domain_id_, "auv_bag_record"});
  inspector_ = std::make_unique<interfaces::GraphInspector>(vendor_, domain_id_);
  running_ = true;
  discovery_ = std::thread([this] { discoveryLoop(); });
}

bool Recorder::wanted(const std::string& topic) const {
  const auto has = [&](const std::vector<std::string>& list) {
    return std::find(list.begin(), list.end(), topic) != list.end();
  };
  return (options_.topics.empty() || has(options_.topics)) && !has(options_.exclude);
}

void Recorder::discoveryLoop() {
  using Clock = std::chrono::steady_clock;
  auto next_flush = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(options_.flush_period_s));
  while (running_) {
    // New topics are looked for every 100 ms (and stop() and the flush are seen as often).
    inspector_->waitFor([](const GraphSnapshot&) { return false; }, std::chrono::milliseconds(100));
    if (!running_) break;
    subscribeNew();
    if (Clock::now() >= next_flush) {
      std::lock_guard<std::mutex> lock(mutex_);
      writer_->flush();
      next_flush = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(options_.flush_period_s));
    }
  }
}

void Recorder::subscribeNew() {
  const GraphSnapshot graph = inspector_->snapshot();
  for (const auto& [topic, types] : graph.topicTypes()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (topics_.count(topic) || skipped_.count(topic) || !wanted(topic)) continue;
    }
    const auto writers = graph.endpointsOn(topic, true);
    if (writers.empty()) continue;  // only readers so far: nothing to record yet
    if (types.size() > 1) {
      std::lock_guard<std::mutex> lock(mutex_);
      skipped_[topic] = "announced with " + std::to_string(types.size()) + " types";
      continue;
    }
    const std::string& type_name = *types.begin();
    const msg::TypeSupport* type = nullptr;
    try {
      type = &interfaces::typeSupportByName(type_name);
    } catch (const std::invalid_argument&) {
      std::lock_guard<std::mutex> lock(mutex_);
      skipped_[topic] = "type '" + type_name + "' is not one of auv-inspect's messages";
      continue;
    }
    const interfaces::QosProfile qos =
        interfaces::compatibleReaderQos(writers, options_.reader_depth);
    auto entry = std::make_unique<Topic>();
    entry->stats.topic = topic;
    entry->stats.type = type_name;
    entry->stats.reliable = qos.reliability == interfaces::Reliability::RELIABLE;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const uint16_t schema = writer_->addSchema(type_name, "omgidl", type->omg_idl);
      entry->channel =
          writer_->addChannel(schema, topic, "cdr", channelMetadata(type_name, writers, qos));
    }
    Topic& recorded = *entry;
    // The reader's callback runs on a middleware thread as soon as it exists: the entry is
    // in topics_ before samples can reach it.
    {
      std::lock_guard<std::mutex> lock(mutex_);
      topics_[topic] = std::move(entry);
    }
    auto reader = participant_->createSerializedReader(
        topic, *type, qos, [this, &recorded](SerializedReader& r) { onSamples(recorded, r); });
    std::lock_guard<std::mutex> lock(mutex_);
    recorded.reader = std::move(reader);
  }
}

void Recorder::onSamples(Topic& topic, SerializedReader& reader) {
  std::lock_guard<std::mutex> lock(mutex_);
  while (reader.take(topic.sample)) {
    const SerializedSample& s = topic.sample;
    if (s.sequence_number > 0) {
      auto [last, first] = topic.last_sequence.try_emplace(s.publication, s.sequence_number);
      if (!first) {
        if (s.sequence_number > last->second + 1)
          topic.stats.lost += static_cast<uint64_t>(s.sequence_number - last->second - 1);
        last->second = std::max(last->second, s.sequence_number);
      }
    }
    writer_->write(topic.channel, ++topic.sequence, static_cast<uint64_t>(s.reception_timestamp_ns),
                   static_cast<uint64_t>(s.source_timestamp_ns), s.cdr);
    ++topic.stats.messages;
    topic.stats.bytes += s.cdr.size();
  }
}

void Recorder::stop() {
  if (!writer_->isOpen()) return;
  running_ = false;
  if (discovery_.joinable()) discovery_.join();
  // Readers first (their callbacks take the lock), then the participants.
  std::map<std::string, std::unique_ptr<SerializedReader>> readers;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [name, topic] : topics_) readers[name] = std::move(topic->reader);
  }
  readers.clear();
  inspector_.reset();
  participant_.reset();
  const RecorderStats summary = stats();
  StringMap recording = {{"vendor", interfaces::toString(vendor_)},
                         {"domain_id", std::to_string(domain_id_)}};
  for (const auto& topic : summary.topics)
    recording["lost:" + topic.topic] = std::to_string(topic.lost);
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [topic, why] : skipped_) recording["skipped:" + topic] = why;
  writer_->addMetadata("auv_bag_record", recording);
  writer_->close();
}

RecorderStats Recorder::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  RecorderStats stats;
  for (const auto& [name, topic] : topics_) stats.topics.push_back(topic->stats);
  for (const auto& [topic, why] : skipped_) stats.skipped.push_back(topic + ": " + why);
  stats.writer = writer_->stats();
  return stats;
}

size_t Recorder::recordedTopics() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return topics_.size();
}

}  // namespace auv::bag
