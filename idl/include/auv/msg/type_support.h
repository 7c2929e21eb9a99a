#pragma once
// Type support shared by every message of the auv message set: what the middleware needs to
// carry a type on either DDS vendor and what the CLI needs to print or build any message.

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>
#include <yaml-cpp/yaml.h>
#include <fastdds/dds/topic/TopicDataType.hpp>

namespace auv::msg {

/// Compile-time facts about one IDL struct; specialised by the generated `auv/msg/all.h`.
template <class T>
struct MessageTraits;

/// Value names of one IDL enum; specialised by the generated `auv/msg/all.h`.
template <class T>
struct EnumTraits {
  static constexpr bool kIsEnum = false;
};

/// Run-time description of one message type, used where the type is only known by name.
struct TypeSupport {
  std::string name;    ///< DDS type name, identical on both vendors, e.g. "auv::msg::Odometry".
  bool keyed = false;  ///< True when the type has @key members (instances matter).
  /// Self-contained OMG IDL of the type: its declaration and every struct and enum it uses,
  /// in dependency order, generated from idl/msg/*.idl. The schema of MCAP and Foxglove's
  /// `omgidl` encoding, named `name`; how it is normalised: idl/README.md, "Schemas".
  const char* omg_idl = "";
  /// A new Fast DDS TopicDataType (fastddsgen's CDR code); the caller owns it.
  std::function<eprosima::fastdds::dds::TopicDataType*()> make_topic_data_type;
  std::function<std::shared_ptr<void>()> create_sample;  ///< A default-constructed sample.
  std::function<YAML::Node(const void*)> to_yaml;        ///< Sample -> YAML map of its fields.
  /// Fills a sample from YAML; throws std::invalid_argument naming the offending field.
  std::function<void(const YAML::Node&, void*)> from_yaml;
};

/// Every type of the message set (generated).
const std::vector<TypeSupport>& allTypes();

/// The type called `name` ("auv::msg::X", "auv/msg/X" or just "X"), or nullptr.
const TypeSupport* findType(const std::string& name);

/// A sample of `type` with text in its strings and an element in each of its sequences (nested
/// ones too), as its from_yaml takes them: for tests and fuzz seeds, which need more than
/// default-constructed samples.
std::shared_ptr<void> filledSample(const TypeSupport& type);

namespace detail {
/// Moves `cdr` `bytes` ahead; throws fastcdr's NotEnoughMemoryException past the end.
void skipCdr(eprosima::fastcdr::Cdr& cdr, size_t bytes);
}  // namespace detail

/// True when `payload` holds a whole sample of T: every element its sequences claim is there
/// (walked with MessageTraits<T>::walkCdr, in the payload's encapsulation).
template <class T>
bool holdsWholeSample(const eprosima::fastrtps::rtps::SerializedPayload_t& payload) {
  eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload.data), payload.length);
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN,
                             eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.read_encapsulation();
    MessageTraits<T>::walkCdr(cdr);
  } catch (const eprosima::fastcdr::exception::Exception&) {
    return false;
  }
  return true;
}

/// fastddsgen's TopicDataType of T, hardened for bytes from outside (the wire, a bag, a
/// viewer), so both vendors drop bad data instead of taking the process down:
///  * a payload is walked before it is decoded: fastcdr sizes a sequence from its length
///    field, checked only against the bytes left, so a 1 MB sample claiming a million
///    structs cost ~560 MB; a sample whose elements are not all there is refused first;
///  * any exception of a malformed payload is a failed deserialize (fastddsgen's code only
///    catches NotEnoughMemoryException).
template <class T>
class GuardedPubSubType : public MessageTraits<T>::PubSubType {
  using Generated = typename MessageTraits<T>::PubSubType;

 public:
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    try {
      return holdsWholeSample<T>(*payload) && Generated::deserialize(payload, data);
    } catch (...) {
      return false;
    }
  }
  /// The generated key computation throws on a key field longer than the key allows (a string
  /// over 255 bytes): the answer is false instead, so such a sample is refused (Fast DDS drops
  /// it; the Cyclone sertype and the serialized writer check the answer), not a crash.
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* handle,
              bool force_md5 = false) override {
    try {
      return Generated::getKey(data, handle, force_md5);
    } catch (...) {
      return false;
    }
  }
};

/// Builds the TypeSupport of a generated message type.
template <class T>
TypeSupport makeTypeSupport() {
  using Traits = MessageTraits<T>;
  TypeSupport ts;
  ts.name = Traits::kTypeName;
  ts.keyed = Traits::kKeyed;
  ts.omg_idl = Traits::omgIdl();
  ts.make_topic_data_type = [] { return new GuardedPubSubType<T>(); };
  ts.create_sample = [] { return std::shared_ptr<void>(std::make_shared<T>()); };
  ts.to_yaml = [](const void* sample) { return toYaml(*static_cast<const T*>(sample)); };
  ts.from_yaml = [](const YAML::Node& node, void* sample) {
    fromYaml(node, *static_cast<T*>(sample), "");
  };
  return ts;
}

}  // namespace auv::msg
