#pragma once
// The `recorder` component (`auv run recorder -p root:=<dir> -p vehicle_name:=<name>`): serves
// the catalogue of a recordings root and chunks of its files to the shore, per
// idl/msg/recorder.idl and the transfer protocol (components/transfer/README.md), under
// `<vehicle_name>/recorder/...`:
//   list_recordings (service, bulk_transfer)  the catalogue
//   fetch_chunk     (service, bulk_transfer)  bytes of a complete recording or sidecar
//   recordings      (topic, latched_state)    one RecordingInfo per file as it changes
// A scanner thread keeps the catalogue up to date (hashing is slow; services stay responsive);
// the services run on the executor.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "auv/config/option_table.h"
#include "auv/interfaces/component.h"
#include "auv/recorder/catalogue.h"
#include "auv/transfer/chunk_reader.h"

namespace auv::recorder {

/// Catalogue entry as the wire message.
msg::RecordingInfo toRecordingInfo(const Recording& recording);

class RecorderComponent : public interfaces::Component {
 public:
  struct Options {
    std::string root;                  ///< recordings root
    std::string vehicle_name = "auv";  ///< prefix of every DDS name
    double scan_period = 2.0;          ///< s between catalogue scans
    uint32_t max_chunk_bytes = 1u << 20;
    std::vector<std::string> extensions = {".mp4"};
    /// The fields with meaning, unit and range: check() and the parameters come from it.
    static const config::OptionTable<Options>& table();
    /// Throws std::invalid_argument naming the parameter.
    void check() const;
  };

  ~RecorderComponent() override;
  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// Runs one scan now, on the caller's thread (tests).
  void scanNow();
  const Catalogue& catalogue() const { return *catalogue_; }
  /// Chunks served (all outcomes) since configure.
  uint64_t chunksServed() const { return chunks_served_; }
  /// Called on the executor thread for every chunk served with data (path, offset, bytes):
  /// lets tests and benchmarks count what crossed the link. Set before activate().
  using ChunkObserver = std::function<void(const std::string&, uint64_t, uint64_t)>;
  void setChunkObserver(ChunkObserver observer) { chunk_observer_ = std::move(observer); }

 private:
  void onList(const msg::RecordingCatalogueRequest& request, msg::RecordingCatalogueReply& reply);
  void onFetch(const msg::FileChunkRequest& request, msg::FileChunkReply& reply);
  void scanLoop();
  void scanAndPublish();
  void requestScan();  // wakes the scanner thread before its period ends
  void stopScanner();

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::unique_ptr<Catalogue> catalogue_;
  std::unique_ptr<transfer::ChunkReader> reader_;
  std::atomic<uint64_t> chunks_served_{0};
  ChunkObserver chunk_observer_;

  std::mutex publish_mutex_;  // scans from the scanner thread and scanNow()
  std::map<std::string, msg::RecordingInfo> published_;

  std::mutex scanner_mutex_;
  std::condition_variable scanner_wake_;
  bool scanner_stop_ = false;
  bool scan_requested_ = false;
  std::thread scanner_;

  std::shared_ptr<interfaces::Publisher<msg::RecordingInfo>> feed_pub_;
  std::shared_ptr<interfaces::Service<msg::RecordingCatalogueRequest, msg::RecordingCatalogueReply>>
      list_service_;
  std::shared_ptr<interfaces::Service<msg::FileChunkRequest, msg::FileChunkReply>> fetch_service_;
};

}  // namespace auv::recorder
