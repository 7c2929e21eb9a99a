#pragma once
// Type-erased DDS access: endpoints that carry samples as their CDR bytes, for tools that
// handle every topic without knowing its C++ type — a recorder writing MCAP, a bridge to
// Foxglove clients. The bytes are the sample's serialized payload as on the wire: the 4-byte
// encapsulation header (XCDR1, CDR_LE or CDR_BE) and the body, which the schema of
// msg::TypeSupport::omg_idl describes. What is and is not byte-identical per vendor:
// docs/architecture.md, "Serialized endpoints".
//
//   auto participant = createParticipant(Vendor::FASTDDS, {domain, "auv_bag"});
//   auto reader = participant->createSerializedReader(
//       "/nav/odometry", typeSupportByName("auv::msg::Odometry"), stateQos(),
//       [](SerializedReader& r) { SerializedSample s; while (r.take(s)) store(s); });
//
// A participant uses a type name either for typed or for serialized endpoints, not both
// (Fast DDS registers one TopicDataType per type name and participant): give serialized
// endpoints a participant of their own, as a recorder or a bridge does anyway.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "auv/interfaces/backend.h"

namespace auv::interfaces {

/// One sample as it travelled.
struct SerializedSample {
  /// Encapsulation header + CDR body. A reader delivers what the writer serialized,
  /// possibly followed by up to 3 bytes of RTPS alignment padding (docs/architecture.md).
  std::vector<uint8_t> cdr;
  int64_t source_timestamp_ns = 0;     ///< The writer's clock when it wrote (system time).
  int64_t reception_timestamp_ns = 0;  ///< This process's system clock when it arrived.
  Guid publication{};                  ///< GUID of the writer.
  /// The writer's RTPS sequence number (from 1, +1 per sample it wrote, so gaps show lost
  /// samples); -1 when the vendor does not say (a Cyclone reader of a writer in its process).
  int64_t sequence_number = -1;
};

/// Writes CDR bytes as samples of one topic; readers of either kind and vendor get them.
class SerializedWriter {
 public:
  virtual ~SerializedWriter() = default;
  /// Publishes `size` bytes (encapsulation header first) as one sample, unchanged. Throws
  /// std::invalid_argument when they do not start with an XCDR1 header (00 00 or 00 01) or,
  /// for a keyed type, do not decode or hold a key longer than the type allows (its key could
  /// not be found), and std::runtime_error when the middleware refuses the write. The body of
  /// an unkeyed type is not checked: typed readers drop a sample they cannot decode.
  virtual void write(const uint8_t* cdr, size_t size) = 0;
  void write(const std::vector<uint8_t>& cdr) { write(cdr.data(), cdr.size()); }
  /// Number of currently matched readers (both vendors).
  virtual int matchedReaders() const = 0;
  /// Waits until every matched reliable reader acknowledged what was written; false on
  /// timeout.
  virtual bool waitForAcknowledgments(double timeout_s) = 0;
  virtual Guid guid() const = 0;
};

/// Reads the samples of one topic as CDR bytes.
class SerializedReader {
 public:
  virtual ~SerializedReader() = default;
  /// Takes the next sample with data into `sample` (its buffer is reused); false when none
  /// is left.
  virtual bool take(SerializedSample& sample) = 0;
  /// Number of currently matched writers (both vendors).
  virtual int matchedWriters() const = 0;
  virtual Guid guid() const = 0;
};

/// The type support called `type_name` ("auv::msg::X", "auv/msg/X" or "X"); throws
/// std::invalid_argument naming it otherwise.
const msg::TypeSupport& typeSupportByName(const std::string& type_name);

/// Decodes serialized bytes (encapsulation header first, as SerializedSample::cdr holds them)
/// into `sample`, a sample of `type` (TypeSupport::create_sample): for a tool that reads one
/// topic of a bag or a bridge in C++. False when they do not decode; never throws for bad
/// bytes.
bool decodeSerialized(const msg::TypeSupport& type, const uint8_t* cdr, size_t size, void* sample);
inline bool decodeSerialized(const msg::TypeSupport& type, const std::vector<uint8_t>& cdr,
                             void* sample) {
  return decodeSerialized(type, cdr.data(), cdr.size(), sample);
}

/// Whether `size` bytes start with an encapsulation header of XCDR1 (CDR_BE or CDR_LE),
/// what every type of this message set uses on both vendors.
bool hasXcdr1Header(const uint8_t* cdr, size_t size);

}  // namespace auv::interfaces
