#pragma once
// Helpers of the serialized endpoint tests (serialized_test.cc, foxglove_decode_test.cc).

#include <gtest/gtest.h>

#include <fastdds/dds/topic/TopicDataType.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "auv/interfaces/serialized.h"

namespace auv::interfaces::test {

struct VendorPair {
  Vendor writer;
  Vendor reader;
};

inline const std::vector<VendorPair> kPairs = {
    {Vendor::CYCLONEDDS, Vendor::CYCLONEDDS},
    {Vendor::FASTDDS, Vendor::FASTDDS},
    {Vendor::FASTDDS, Vendor::CYCLONEDDS},
    {Vendor::CYCLONEDDS, Vendor::FASTDDS},
};

inline std::string pairName(const VendorPair& pair) {
  return toString(pair.writer) + "_to_" + toString(pair.reader);
}

/// The CDR of `sample` as the type's own TopicDataType writes it (encapsulation included)
/// into a buffer filled with `fill`: fastcdr skips alignment gaps without writing them.
inline std::vector<uint8_t> cdrOf(const msg::TypeSupport& type, const void* sample,
                                  uint8_t fill = 0) {
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(type.make_topic_data_type());
  void* data = const_cast<void*>(sample);
  eprosima::fastrtps::rtps::SerializedPayload_t payload(tdt->getSerializedSizeProvider(data)());
  std::memset(payload.data, fill, payload.max_size);
  if (!tdt->serialize(data, &payload)) throw std::runtime_error("serialize failed");
  return std::vector<uint8_t>(payload.data, payload.data + payload.length);
}

/// Where `sample`'s CDR has alignment gaps: the bytes two fills leave different.
inline std::vector<bool> alignmentGaps(const msg::TypeSupport& type, const void* sample) {
  const std::vector<uint8_t> zeros = cdrOf(type, sample, 0x00);
  const std::vector<uint8_t> ones = cdrOf(type, sample, 0xff);
  std::vector<bool> gaps(zeros.size());
  for (size_t i = 0; i < zeros.size(); ++i) gaps[i] = zeros[i] != ones[i];
  return gaps;
}

/// Decodes `cdr` as `type` into `sample`; false when it does not decode.
inline bool decodeInto(const msg::TypeSupport& type, const std::vector<uint8_t>& cdr,
                       void* sample) {
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(type.make_topic_data_type());
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(cdr.size()));
  std::memcpy(payload.data, cdr.data(), cdr.size());
  payload.length = static_cast<uint32_t>(cdr.size());
  return tdt->deserialize(&payload, sample);
}

template <class T>
T decode(const msg::TypeSupport& type, const std::vector<uint8_t>& cdr) {
  T sample;
  EXPECT_TRUE(decodeInto(type, cdr, &sample)) << type.name << " did not decode";
  return sample;
}

/// `received` is `sent` (alignment gaps zero), except that
///  * over the network it may end in up to 3 zero bytes up to a multiple of 4: RTPS aligns
///    submessages to 4 bytes and neither vendor's writer counts that padding in the
///    encapsulation options, so a reader cannot tell it from data;
///  * with `gaps` (alignmentGaps), bytes in alignment gaps may differ: a Fast DDS writer
///    reuses payload buffers, and fastcdr leaves the gaps as the last sample there left them.
inline void expectWireBytes(const std::vector<uint8_t>& received, const std::vector<uint8_t>& sent,
                            const std::vector<bool>& gaps = {}) {
  ASSERT_GE(received.size(), sent.size());
  for (size_t i = 0; i < sent.size(); ++i) {
    if (received[i] == sent[i] || (i < gaps.size() && gaps[i])) continue;
    ADD_FAILURE() << "byte " << i << " of " << sent.size() << ": sent " << int(sent[i])
                  << ", received " << int(received[i]);
    return;
  }
  if (received.size() == sent.size()) return;
  EXPECT_LT(received.size() - sent.size(), 4u);
  EXPECT_EQ(received.size() % 4, 0u) << received.size() << " bytes for " << sent.size();
  for (size_t i = sent.size(); i < received.size(); ++i) EXPECT_EQ(received[i], 0) << i;
}

/// Collects what a serialized reader takes, from the middleware thread.
class Collector {
 public:
  SerializedDataCallback callback() {
    return [this](SerializedReader& reader) {
      SerializedSample sample;
      while (reader.take(sample)) {
        std::lock_guard<std::mutex> lock(mutex_);
        samples_.push_back(sample);
        changed_.notify_all();
      }
    };
  }
  bool waitFor(size_t count, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return samples_.size() >= count; });
  }
  std::vector<SerializedSample> samples() {
    std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }
  size_t size() {
    std::lock_guard<std::mutex> lock(mutex_);
    return samples_.size();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<SerializedSample> samples_;
};

}  // namespace auv::interfaces::test
