// Fuzz harness: CDR deserialization of every type of the message set on both vendors' type
// support, as samples come in from outside (the wire, a bag being played, a Foxglove viewer):
//  * a typed reader: Fast DDS's TopicDataType (fastddsgen's code behind GuardedPubSubType)
//    decodes the payload and, for a keyed type without a key hash, the key is computed from the
//    decoded sample (Fast DDS's reader history); Cyclone's sertype makes a serdata of the bytes
//    (a keyed type is decoded for its key) and a sample of that (to_sample);
//  * a serialized reader (the bag recorder, the Foxglove bridge): each vendor's serialized type
//    support takes the bytes as they are and finds a keyed sample's key by decoding them;
//  * a serialized writer (the bag player): SerializedWriter::write checks the bytes, then hands
//    them to the vendor's serialized type support as its DataWriter would;
//  * decodeSerialized (tools reading a bag, the bridge's camera images).
// Input: byte 0 selects the type (byte / 4 modulo the number of types, in msg::allTypes() order:
// 64 types at most) and the endpoints (byte % 4: 0 Fast DDS typed, 1 Cyclone typed, 2 Fast DDS
// serialized, 3 Cyclone serialized); the rest is the payload, encapsulation header first.
// A clear error is SerializedWriter::write's std::invalid_argument; the others refuse bad bytes
// by their return value (false, nullptr, a failed take). Any other exception, a crash or a
// sanitizer report is a bug.
#include <fastdds/dds/topic/TopicDataType.hpp>  // before Cyclone's headers (PID_* macros)

#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>

#include "../src/cyclonedds/cyclone_sertype.h"
#include "../src/fastdds/fastdds_raw_type.h"
#include "../src/serialized_sample.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/type_support.h"

namespace {

using auv::interfaces::DataWriter;
using auv::interfaces::Guid;
using auv::interfaces::Vendor;
using auv::interfaces::detail::RawSample;
using auv::msg::TypeSupport;
using eprosima::fastdds::dds::TopicDataType;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

// A SerializedPayload_t over bytes it does not own, as the vendors hand received bytes over.
struct BorrowedPayload : SerializedPayload_t {
  BorrowedPayload(const uint8_t* bytes, size_t size) {
    data = const_cast<uint8_t*>(bytes);
    length = static_cast<uint32_t>(size);
    max_size = length;
  }
  ~BorrowedPayload() { data = nullptr; }
};

struct FreeSertype {
  void operator()(ddsi_sertype* sertype) const { ddsi_sertype_free(sertype); }
};
using SertypePtr = std::unique_ptr<ddsi_sertype, FreeSertype>;

// Per type, what a participant registers for it; made once, as a participant does.
struct TypeEndpoints {
  const TypeSupport* type;
  std::unique_ptr<TopicDataType> typed;  // Fast DDS typed endpoints
  std::unique_ptr<TopicDataType> raw;    // Fast DDS serialized endpoints
  SertypePtr cyclone_typed;              // Cyclone typed endpoints
  SertypePtr cyclone_serialized;         // Cyclone serialized endpoints
};

std::vector<TypeEndpoints>& endpoints() {
  static std::vector<TypeEndpoints> all = [] {
    std::vector<TypeEndpoints> made;
    for (const TypeSupport& type : auv::msg::allTypes()) {
      made.push_back(TypeEndpoints{&type,
                                   std::unique_ptr<TopicDataType>(type.make_topic_data_type()),
                                   std::make_unique<auv::interfaces::detail::RawPubSubType>(type),
                                   SertypePtr(auv::interfaces::detail::createSertype(type, false)),
                                   SertypePtr(auv::interfaces::detail::createSertype(type, true))});
    }
    return made;
  }();
  return all;
}

// The DataWriter under a serialized writer, without a network: what a vendor's DataWriter does
// with the RawSample it is given, up to the bytes it would send.
class LoopbackWriter : public DataWriter {
 public:
  LoopbackWriter(TypeEndpoints& t, Vendor vendor) : t_(t), vendor_(vendor) {}
  void write(const void* sample) override {
    auto* raw = const_cast<RawSample*>(static_cast<const RawSample*>(sample));
    if (vendor_ == Vendor::FASTDDS) {
      // Fast DDS keys the sample (ignoring a failure) and serializes it into a pool payload.
      if (t_.type->keyed) {
        InstanceHandle_t handle;
        t_.raw->getKey(raw, &handle, false);
      }
      SerializedPayload_t payload(t_.raw->getSerializedSizeProvider(raw)());
      if (!t_.raw->serialize(raw, &payload)) throw std::runtime_error("fastdds: write");
    } else {
      // dds_write fails when the sertype makes no serdata (the backend throws for it).
      ddsi_serdata* d = ddsi_serdata_from_sample(t_.cyclone_serialized.get(), SDK_DATA, raw);
      if (d == nullptr) throw std::runtime_error("cyclonedds: write");
      ddsi_serdata_unref(d);
    }
  }
  int matchedReaders() const override { return 0; }
  bool waitForAcknowledgments(double) override { return true; }
  Guid guid() const override { return Guid{}; }

 private:
  TypeEndpoints& t_;
  Vendor vendor_;
};

// As the bag player plays a message: std::invalid_argument is its refusal of the bytes. The
// middleware refusing them after that (std::runtime_error) would end the player: a bug.
void playBack(TypeEndpoints& t, Vendor vendor, const uint8_t* cdr, size_t size) {
  auto writer = auv::interfaces::detail::makeSerializedWriter(
      std::make_unique<LoopbackWriter>(t, vendor), *t.type);
  try {
    writer->write(cdr, size);
  } catch (const std::invalid_argument&) {
  }
}

// A typed reader and the tools that decode bytes into a sample.
void fastDdsTyped(TypeEndpoints& t, const uint8_t* cdr, size_t size) {
  auto sample = t.type->create_sample();
  BorrowedPayload payload(cdr, size);
  if (t.typed->deserialize(&payload, sample.get()) && t.type->keyed) {
    InstanceHandle_t handle;
    t.typed->getKey(sample.get(), &handle, false);
    t.typed->getKey(sample.get(), &handle, true);
  }
  auto decoded = t.type->create_sample();
  auv::interfaces::decodeSerialized(*t.type, cdr, size, decoded.get());
}

// A serialized reader (which keys a keyed sample by decoding it) and a serialized writer.
void fastDdsSerialized(TypeEndpoints& t, const uint8_t* cdr, size_t size) {
  RawSample raw;
  BorrowedPayload payload(cdr, size);
  if (t.raw->deserialize(&payload, &raw) && t.type->keyed) {
    InstanceHandle_t handle;
    t.raw->getKey(&raw, &handle, false);
  }
  playBack(t, Vendor::FASTDDS, cdr, size);
}

// A serdata of received bytes, converted into `sample` as a reader's take does.
void receive(ddsi_sertype* sertype, const uint8_t* cdr, size_t size, void* sample) {
  ddsrt_iovec_t iov;
  iov.iov_base = const_cast<uint8_t*>(cdr);
  iov.iov_len = static_cast<ddsrt_iov_len_t>(size);
  ddsi_serdata* d = ddsi_serdata_from_ser_iov(sertype, SDK_DATA, 1, &iov, size);
  if (d == nullptr) return;  // dropped on arrival
  ddsi_serdata_to_sample(d, sample, nullptr, nullptr);
  auv::interfaces::detail::takeFailed();  // the reader's flag of a sample it drops
  ddsi_serdata_unref(d);
}

void cycloneTyped(TypeEndpoints& t, const uint8_t* cdr, size_t size) {
  auto sample = t.type->create_sample();
  receive(t.cyclone_typed.get(), cdr, size, sample.get());
}

void cycloneSerialized(TypeEndpoints& t, const uint8_t* cdr, size_t size) {
  RawSample raw;
  receive(t.cyclone_serialized.get(), cdr, size, &raw);
  playBack(t, Vendor::CYCLONEDDS, cdr, size);
}

// The endpoints input byte 0 chooses, by its value modulo 4.
using Endpoint = void (*)(TypeEndpoints&, const uint8_t*, size_t);
constexpr Endpoint kEndpoints[4] = {fastDdsTyped, cycloneTyped, fastDdsSerialized,
                                    cycloneSerialized};

// ---- seeds

// `sample` as a Fast DDS writer serializes it.
std::string fastDdsBytes(TypeEndpoints& t, void* sample) {
  SerializedPayload_t payload(t.typed->getSerializedSizeProvider(sample)());
  std::memset(payload.data, 0, payload.max_size);
  if (!t.typed->serialize(sample, &payload)) throw std::runtime_error("serialize " + t.type->name);
  return std::string(reinterpret_cast<const char*>(payload.data), payload.length);
}

// `sample` as a Cyclone writer serializes it (our sertype's from_sample, then to_ser).
std::string cycloneBytes(TypeEndpoints& t, const void* sample) {
  ddsi_serdata* d = ddsi_serdata_from_sample(t.cyclone_typed.get(), SDK_DATA, sample);
  if (d == nullptr) throw std::runtime_error("cyclone serdata of " + t.type->name);
  std::string bytes(ddsi_serdata_size(d), '\0');
  ddsi_serdata_to_ser(d, 0, bytes.size(), bytes.data());
  ddsi_serdata_unref(d);
  return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  std::vector<TypeEndpoints>& all = endpoints();
  kEndpoints[data[0] % 4](all[(data[0] / 4) % all.size()], data + 1, size - 1);
  return 0;
}

/// Every type, default-constructed and with its strings and sequences filled, as each vendor
/// writes it, for each endpoint of that vendor.
std::vector<std::string> auvFuzzSeeds() {
  std::vector<std::string> seeds;
  std::vector<TypeEndpoints>& all = endpoints();
  for (size_t i = 0; i < all.size(); ++i) {
    TypeEndpoints& t = all[i];
    for (const auto& sample : {t.type->create_sample(), auv::msg::filledSample(*t.type)}) {
      const std::string bytes[2] = {fastDdsBytes(t, sample.get()), cycloneBytes(t, sample.get())};
      for (uint8_t endpoint = 0; endpoint < 4; ++endpoint) {
        const std::string& cdr = bytes[endpoint % 2];  // the vendor of the endpoint
        seeds.push_back(std::string(1, static_cast<char>(4 * i + endpoint)) + cdr);
      }
    }
  }
  return seeds;
}
