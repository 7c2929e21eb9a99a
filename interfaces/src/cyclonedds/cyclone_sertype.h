#pragma once
// A Cyclone DDS custom sertype that carries the fastddsgen C++ types: its hooks call the
// type's Fast DDS TopicDataType to serialize, deserialize and compute keys. This gives both
// vendors one C++ type per message and identical XCDR1 bytes on the wire (docs/library-notes.md,
// "One C++ type for both vendors"). Uses Cyclone 0.10 internal headers: pinned to 0.10.x.

#include <memory>

#include "auv/msg/type_support.h"

struct ddsi_sertype;

namespace auv::interfaces::detail {

/// A new sertype for `type`; ownership passes to dds_create_topic_sertype.
ddsi_sertype* createSertype(const msg::TypeSupport& type);

}  // namespace auv::interfaces::detail
