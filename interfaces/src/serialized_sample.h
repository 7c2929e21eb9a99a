#pragma once
// The sample type of serialized endpoints inside the backends. A serialized endpoint is a
// vendor's ordinary DataWriter/DataReader over a type support that moves bytes instead of
// (de)serializing: Fast DDS's RawPubSubType (fastdds_raw_type.h) and Cyclone's serialized
// sertype (cyclone_sertype.h) read a RawSample when writing and fill one when reading. The
// adapters below turn those endpoints into SerializedWriter/SerializedReader.

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "auv/interfaces/serialized.h"

namespace auv::interfaces::detail {

struct RawSample {
  const uint8_t* view = nullptr;  ///< Writing: the bytes to send (not owned).
  size_t view_size = 0;
  std::vector<uint8_t> bytes;          ///< Reading: the bytes received.
  int64_t reception_timestamp_ns = 0;  ///< Reading: set by type supports that know it.
  int64_t sequence_number = -1;        ///< Reading: set by type supports that know it.

  const uint8_t* data() const { return view != nullptr ? view : bytes.data(); }
  size_t size() const { return view != nullptr ? view_size : bytes.size(); }
};

/// A SerializedWriter over a backend writer whose type support takes RawSamples.
std::unique_ptr<SerializedWriter> makeSerializedWriter(std::unique_ptr<DataWriter> writer,
                                                       const msg::TypeSupport& type);

/// A SerializedReader over a backend reader whose type support fills RawSamples. Create it
/// first, create the backend reader with dataCallback(), then attach() that reader.
class SerializedReaderAdapter : public SerializedReader {
 public:
  explicit SerializedReaderAdapter(SerializedDataCallback on_data) : on_data_(std::move(on_data)) {}
  /// The callback for the backend reader. It may run before attach() (history of a writer in
  /// the same process): it then remembers the reader it was given.
  DataCallback dataCallback();
  void attach(std::unique_ptr<DataReader> reader);

  bool take(SerializedSample& sample) override;
  int matchedWriters() const override { return reader_.load()->matchedWriters(); }
  Guid guid() const override { return reader_.load()->guid(); }

 private:
  SerializedDataCallback on_data_;
  std::atomic<DataReader*> reader_{nullptr};
  std::unique_ptr<DataReader> owned_;  // last: destroyed first, while on_data_ still exists
};

}  // namespace auv::interfaces::detail
