// Vendor-neutral half of the serialized endpoints (serialized.h): the adapters over the
// backends' raw readers and writers, header checks, type lookup.
#include "auv/interfaces/serialized.h"

#include <fastdds/dds/topic/TopicDataType.hpp>

#include <chrono>
#include <mutex>
#include <stdexcept>

#include "serialized_sample.h"

namespace auv::interfaces {

const msg::TypeSupport& typeSupportByName(const std::string& type_name) {
  if (const msg::TypeSupport* type = msg::findType(type_name)) return *type;
  throw std::invalid_argument("unknown message type '" + type_name +
                              "' (`auv interface list` shows the known ones)");
}

bool hasXcdr1Header(const uint8_t* cdr, size_t size) {
  // Representation identifier, big endian: 0x0000 CDR_BE, 0x0001 CDR_LE. The two option
  // bytes that follow are free.
  return size >= 4 && cdr[0] == 0 && (cdr[1] == 0 || cdr[1] == 1);
}

namespace detail {
namespace {

int64_t systemNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A SerializedPayload_t over bytes it does not own (its destructor would free `data`).
struct BorrowedPayload : eprosima::fastrtps::rtps::SerializedPayload_t {
  BorrowedPayload(const uint8_t* bytes, size_t size) {
    data = const_cast<uint8_t*>(bytes);
    length = static_cast<uint32_t>(size);
    max_size = length;
  }
  ~BorrowedPayload() { data = nullptr; }
};

class SerializedWriterAdapter : public SerializedWriter {
 public:
  SerializedWriterAdapter(std::unique_ptr<DataWriter> writer, const msg::TypeSupport& type)
      : writer_(std::move(writer)), type_name_(type.name) {
    if (type.keyed) {
      typed_.reset(type.make_topic_data_type());
      scratch_ = type.create_sample();
    }
  }
  void write(const uint8_t* cdr, size_t size) override {
    if (!hasXcdr1Header(cdr, size))
      throw std::invalid_argument("serialized " + type_name_ +
                                  ": bytes do not start with an XCDR1 encapsulation header");
    if (typed_) checkDecodes(cdr, size);
    RawSample sample;
    sample.view = cdr;
    sample.view_size = size;
    writer_->write(&sample);
  }
  int matchedReaders() const override { return writer_->matchedReaders(); }
  bool waitForAcknowledgments(double timeout_s) override {
    return writer_->waitForAcknowledgments(timeout_s);
  }
  Guid guid() const override { return writer_->guid(); }

 private:
  // A keyed sample's instance is its key, which both vendors find by decoding it: refuse what
  // does not decode here, alike for both (Fast DDS would write it under an undefined key), and
  // what has a key the type cannot compute (a @key string over its 255-byte bound).
  void checkDecodes(const uint8_t* cdr, size_t size) {
    std::lock_guard<std::mutex> lock(mutex_);
    BorrowedPayload payload(cdr, size);
    if (!typed_->deserialize(&payload, scratch_.get()))
      throw std::invalid_argument("serialized " + type_name_ +
                                  ": bytes do not decode, so the sample's key is unknown");
    eprosima::fastrtps::rtps::InstanceHandle_t key;
    if (!typed_->getKey(scratch_.get(), &key, true)) {
      throw std::invalid_argument("serialized " + type_name_ +
                                  ": the sample's key is longer than the type allows (a key "
                                  "string over 255 bytes)");
    }
  }

  std::unique_ptr<DataWriter> writer_;
  std::string type_name_;
  std::mutex mutex_;  // typed_ and scratch_
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> typed_;
  std::shared_ptr<void> scratch_;
};

}  // namespace

std::unique_ptr<SerializedWriter> makeSerializedWriter(std::unique_ptr<DataWriter> writer,
                                                       const msg::TypeSupport& type) {
  return std::make_unique<SerializedWriterAdapter>(std::move(writer), type);
}

DataCallback SerializedReaderAdapter::dataCallback() {
  return [this](DataReader& reader) {
    DataReader* expected = nullptr;
    reader_.compare_exchange_strong(expected, &reader);
    if (on_data_) on_data_(*this);
  };
}

void SerializedReaderAdapter::attach(std::unique_ptr<DataReader> reader) {
  reader_ = reader.get();  // the same reader the callback may have stored already
  owned_ = std::move(reader);
}

bool SerializedReaderAdapter::take(SerializedSample& sample) {
  RawSample raw;
  raw.bytes.swap(sample.cdr);  // reuse the caller's buffer
  SampleInfo info;
  const bool taken = reader_.load()->take(&raw, &info);
  sample.cdr.swap(raw.bytes);
  if (!taken) return false;
  sample.source_timestamp_ns = info.source_timestamp_ns;
  sample.publication = info.publication;
  sample.reception_timestamp_ns = raw.reception_timestamp_ns > 0    ? raw.reception_timestamp_ns
                                  : info.reception_timestamp_ns > 0 ? info.reception_timestamp_ns
                                                                    : systemNowNs();
  sample.sequence_number = raw.sequence_number >= 0 ? raw.sequence_number : info.sequence_number;
  return true;
}

}  // namespace detail

bool decodeSerialized(const msg::TypeSupport& type, const uint8_t* cdr, size_t size, void* sample) {
  // The generated type is guarded (GuardedPubSubType): malformed bytes give false.
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> typed(type.make_topic_data_type());
  detail::BorrowedPayload payload(cdr, size);
  return typed->deserialize(&payload, sample);
}

}  // namespace auv::interfaces
