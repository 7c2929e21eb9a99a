#pragma once
// A Fast DDS TopicDataType for serialized endpoints: serialize() and deserialize() copy the
// payload bytes (encapsulation header included) to and from a detail::RawSample untouched,
// under the real type's name, so it matches typed endpoints of either vendor. Keyed types
// find a sample's key by decoding it with the real type (fastddsgen's getKey).

#include <fastdds/dds/topic/TopicDataType.hpp>

#include <memory>
#include <mutex>

#include "auv/msg/type_support.h"

namespace auv::interfaces::detail {

class RawPubSubType : public eprosima::fastdds::dds::TopicDataType {
 public:
  explicit RawPubSubType(const msg::TypeSupport& type);
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override;
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override;
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override;
  void* createData() override;
  void deleteData(void* data) override;
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle,
              bool force_md5 = false) override;

 private:
  std::mutex key_mutex_;  // typed_'s getKey uses a buffer of its own; several threads call
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> typed_;
  std::shared_ptr<void> scratch_;  // a sample of the real type, to decode keys into
};

}  // namespace auv::interfaces::detail
