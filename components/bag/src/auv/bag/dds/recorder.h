#pragma once
// Records DDS topics of either vendor into an MCAP file, as `auv bag record` and the vehicle
// launch's `record:=true` do: a participant of its own discovers the writers on the domain
// (GraphInspector), subscribes to each topic that passes the filter with serialized readers
// (the CDR bytes as they travelled, no re-encoding) and a QoS that matches every writer, and
// writes one channel per topic with its type's OMG IDL as schema and the offered QoS in the
// channel's metadata (qos_metadata.h). Samples lost on the way are counted from the writers'
// sequence numbers. Layout and guarantees: components/bag/README.md, "Recording".

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/bag/mcap_writer.h"
#include "auv/config/option_table.h"
#include "auv/interfaces/backend.h"
#include "auv/interfaces/graph.h"

namespace auv::bag {

struct RecorderOptions {
  std::string output;                       ///< the .mcap file (written as .part until stop())
  std::vector<std::string> topics;          ///< topics to record ("/a/b" or "a/b"); empty: all
  std::vector<std::string> exclude;         ///< topics never recorded
  std::string vendor;                       ///< cyclonedds or fastdds; empty: AUV_DDS (cyclonedds)
  int domain_id = -1;                       ///< -1: AUV_DOMAIN_ID (0)
  std::string compression = "zstd";         ///< none, zstd or lz4
  uint64_t chunk_size = uint64_t{1} << 20;  ///< bytes of messages per chunk
  double flush_period_s = 1.0;  ///< a chunk is written at least this often (what a crash loses)
  int reader_depth = 100;       ///< keep-last depth of the readers (a burst they absorb)
  bool overwrite = false;       ///< replace an existing output file

  static const config::OptionTable<RecorderOptions>& table();
  /// Throws std::invalid_argument naming the field and the value.
  void check() const;
};

/// What one topic's recording holds.
struct TopicStats {
  std::string topic;
  std::string type;
  uint64_t messages = 0;
  uint64_t bytes = 0;
  /// Samples missing between two a writer wrote (RTPS sequence numbers; a best-effort topic
  /// loses some by design, a reliable one should not).
  uint64_t lost = 0;
  bool reliable = false;
};

struct RecorderStats {
  std::vector<TopicStats> topics;    ///< recorded topics, by name
  std::vector<std::string> skipped;  ///< "topic: why" (unknown type, several types)
  WriterStats writer;
};

class Recorder {
 public:
  /// Checks the options and opens the output (BagError EXISTS/IO naming it). Nothing is
  /// recorded before start().
  explicit Recorder(RecorderOptions options);
  ~Recorder();  ///< stop()s, swallowing errors
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Joins the domain and records every matching topic as it is discovered.
  void start();
  /// Stops reading, writes the summary with the recording's statistics as metadata and
  /// renames the file to its final name. Throws BagError IO (the .part file is kept).
  void stop();

  RecorderStats stats() const;
  /// Topics recorded so far (for a caller that waits for some to appear).
  size_t recordedTopics() const;

 private:
  struct Topic;
  void discoveryLoop();
  void subscribeNew();
  void onSamples(Topic& topic, interfaces::SerializedReader& reader);
  bool wanted(const std::string& topic) const;

  RecorderOptions options_;
  interfaces::Vendor vendor_;
  int domain_id_ = 0;
  std::unique_ptr<interfaces::GraphInspector> inspector_;
  std::unique_ptr<interfaces::Participant> participant_;

  mutable std::mutex mutex_;  // writer_, topics_' counters, skipped_
  std::unique_ptr<McapWriter> writer_;
  std::map<std::string, std::unique_ptr<Topic>> topics_;
  std::map<std::string, std::string> skipped_;  // topic -> why

  std::atomic<bool> running_{false};
  std::thread discovery_;
};

}  // namespace auv::bag
