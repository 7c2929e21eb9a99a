#include "fastdds_raw_type.h"

#include <cstring>

#include "serialized_sample.h"

namespace auv::interfaces::detail {

using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

RawPubSubType::RawPubSubType(const msg::TypeSupport& type)
    : typed_(type.make_topic_data_type()), scratch_(type.create_sample()) {
  setName(type.name.c_str());
  // The real type's size estimate: the initial size of payloads in the writer's pool.
  m_typeSize = typed_->m_typeSize;
  m_isGetKeyDefined = type.keyed;
}

bool RawPubSubType::serialize(void* data, SerializedPayload_t* payload) {
  const auto* sample = static_cast<const RawSample*>(data);
  const size_t size = sample->size();
  if (size < 4 || payload->max_size < size) return false;
  std::memcpy(payload->data, sample->data(), size);
  payload->length = static_cast<uint32_t>(size);
  payload->encapsulation = sample->data()[1] == 0 ? CDR_BE : CDR_LE;
  return true;
}

bool RawPubSubType::deserialize(SerializedPayload_t* payload, void* data) {
  auto* sample = static_cast<RawSample*>(data);
  sample->view = nullptr;
  sample->bytes.assign(payload->data, payload->data + payload->length);
  return true;
}

std::function<uint32_t()> RawPubSubType::getSerializedSizeProvider(void* data) {
  const auto size = static_cast<uint32_t>(static_cast<const RawSample*>(data)->size());
  return [size] { return size; };
}

void* RawPubSubType::createData() { return new RawSample(); }

void RawPubSubType::deleteData(void* data) { delete static_cast<RawSample*>(data); }

bool RawPubSubType::getKey(void* data, InstanceHandle_t* handle, bool force_md5) {
  if (!m_isGetKeyDefined) return false;
  const auto* sample = static_cast<const RawSample*>(data);
  SerializedPayload_t payload;
  payload.data = const_cast<uint8_t*>(sample->data());
  payload.length = static_cast<uint32_t>(sample->size());
  payload.max_size = payload.length;
  std::lock_guard<std::mutex> lock(key_mutex_);
  const bool decoded = typed_->deserialize(&payload, scratch_.get());
  payload.data = nullptr;  // borrowed
  // A key over its bound (a @key string over 255 bytes): no key, and a reader drops the sample.
  return decoded && typed_->getKey(scratch_.get(), handle, force_md5);
}

}  // namespace auv::interfaces::detail
