#pragma once
// A Cyclone DDS custom sertype that carries the fastddsgen C++ types: its hooks call the
// type's Fast DDS TopicDataType to serialize, deserialize and compute keys. This gives both
// vendors one C++ type per message and identical XCDR1 bytes on the wire (docs/library-notes.md,
// "One C++ type for both vendors"). Uses Cyclone 0.10 internal headers: pinned to 0.10.x.

#include <memory>

#include "auv/msg/type_support.h"

struct ddsi_sertype;

namespace auv::interfaces::detail {

/// A new sertype for `type`; ownership passes to dds_create_topic_sertype. `serialized`:
/// samples are detail::RawSamples (serialized_sample.h) whose bytes go to and from the wire
/// untouched, with the reception time and the writer's sequence number when received.
ddsi_sertype* createSertype(const msg::TypeSupport& type, bool serialized = false);

/// True if a sample taken on this thread since the last call could not be converted (a
/// malformed payload); clears the flag. Cyclone 0.10's take ignores the result of a
/// sertype's to_sample and hands such a sample out as valid data, half-filled: readers call
/// this after each dds_take and drop the sample instead.
bool takeFailed();

}  // namespace auv::interfaces::detail
