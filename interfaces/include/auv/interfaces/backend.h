#pragma once
// The vendor-neutral DDS layer underneath Node: one participant per node, typed by the
// fastddsgen TopicDataType of each message (see auv/msg/type_support.h). Components use
// Node/Publisher/Subscription; tools such as the `auv` CLI use this level directly when
// they only know a type by name.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "auv/interfaces/qos.h"
#include "auv/msg/type_support.h"

namespace auv::interfaces {

enum class Vendor { CYCLONEDDS, FASTDDS };

/// "cyclonedds" or "fastdds".
std::string toString(Vendor vendor);
/// Parses "cyclonedds"/"fastdds"; throws std::invalid_argument naming the value otherwise.
Vendor vendorFromString(const std::string& name);
/// The vendor chosen by AUV_DDS (default cyclonedds); throws on an unknown value.
Vendor vendorFromEnvironment();
/// The domain chosen by AUV_DOMAIN_ID (default 0); throws unless it is an integer in [0, 232].
int domainFromEnvironment();

using Guid = std::array<uint8_t, 16>;
/// Hex form "0110a3...": unique per endpoint/participant, printed by the CLI.
std::string toString(const Guid& guid);

/// What came with a taken sample besides its data.
struct SampleInfo {
  int64_t source_timestamp_ns = 0;  ///< Writer's clock at write time (system time).
  Guid publication{};               ///< GUID of the writer that wrote the sample.
  /// This process's system clock when the sample arrived; 0 when the vendor does not say
  /// (Cyclone's typed readers; serialized readers always fill it in).
  int64_t reception_timestamp_ns = 0;
  /// The writer's RTPS sequence number; -1 when the vendor does not say (Cyclone's typed
  /// readers).
  int64_t sequence_number = -1;
};

/// A typed DDS data writer of one vendor.
class DataWriter {
 public:
  virtual ~DataWriter() = default;
  /// Writes one sample (a pointer to the message type); throws std::runtime_error on failure.
  virtual void write(const void* sample) = 0;
  /// Number of currently matched readers (both vendors).
  virtual int matchedReaders() const = 0;
  /// Waits until every matched reliable reader acknowledged what was written; false on
  /// timeout. Lets a short-lived writer (e.g. `auv topic pub --times n`) exit without loss.
  virtual bool waitForAcknowledgments(double timeout_s) = 0;
  virtual Guid guid() const = 0;
};

/// A typed DDS data reader of one vendor.
class DataReader {
 public:
  virtual ~DataReader() = default;
  /// Takes the next valid sample into `sample`; false when none is left.
  virtual bool take(void* sample, SampleInfo* info) = 0;
  /// Called by takeBatch() for each sample with data, in order. `sample` is only valid
  /// during the call.
  using SampleVisitor = std::function<void(const void* sample, const SampleInfo& info)>;
  /// Takes up to `max` samples (at most kMaxBatch) and visits those with data; returns how
  /// many it took, 0 when none was left. `scratch` is a sample of the reader's type a vendor
  /// may deserialize into. Vendors whose reader lock is contended by their own delivery
  /// thread take the whole batch under one lock (docs/performance.md,
  /// "Keep-all streams", item 5).
  /// If a visit throws, the batch's remaining samples are still visited, then the first
  /// exception is rethrown: samples already taken are never lost.
  virtual int takeBatch(void* scratch, int max, const SampleVisitor& visit);
  /// Largest batch: Fast DDS's default max_samples_per_read.
  static constexpr int kMaxBatch = 32;
  /// Number of currently matched writers (both vendors).
  virtual int matchedWriters() const = 0;
  virtual Guid guid() const = 0;
};

/// DDS Security for a participant: one identity of a keystore made by `auv security init`
/// (layout and supported vendor pairings in docs/security.md).
struct SecurityIdentity {
  std::string keystore;  ///< The keystore folder; empty = no security.
  std::string identity;  ///< Name of the identity, a folder under <keystore>/identities/.
  /// Enforce: a missing or unreadable file is an error. Permissive: the participant runs
  /// unsecured instead, with a warning on stderr (ROS 2's ROS_SECURITY_STRATEGY).
  bool enforce = true;
};

/// The six files a secured participant uses (absolute paths, as file: URIs need them).
struct SecurityFiles {
  std::string identity_ca;     ///< <keystore>/ca.cert.pem: CA that signed every identity.
  std::string permissions_ca;  ///< Same CA: it also signs governance and permissions.
  std::string governance;      ///< <keystore>/governance.p7s
  std::string certificate;     ///< <keystore>/identities/<name>/cert.pem
  std::string private_key;     ///< <keystore>/identities/<name>/key.pem
  std::string permissions;     ///< <keystore>/identities/<name>/permissions.p7s
};

/// The keystore layout: where `identity`'s files are (no check that they exist).
SecurityFiles securityFiles(const std::string& keystore, const std::string& identity);

/// Security chosen by AUV_SECURITY_KEYSTORE, AUV_SECURITY_IDENTITY and
/// AUV_SECURITY_STRATEGY (Enforce, the default, or Permissive); nullopt when no keystore is
/// set. Throws std::invalid_argument naming the variable for a missing identity or an
/// unknown strategy.
std::optional<SecurityIdentity> securityFromEnvironment();

/// The files of `security` after checking that each is readable; nullopt when security is
/// off (no keystore, or Permissive with a file missing). Throws std::runtime_error naming
/// the file when it is missing or unreadable under Enforce.
std::optional<SecurityFiles> resolveSecurity(const SecurityIdentity& security);

/// How a participant is created: identity in USER_DATA, domain, security.
struct ParticipantOptions {
  // A constructor rather than an aggregate, so the common `{domain, name}` stays free of
  // missing-initializer warnings.
  ParticipantOptions(int domain = 0, std::string name = "")
      : domain_id(domain), node_name(std::move(name)) {}
  int domain_id = 0;
  std::string node_name;  ///< Shown by `auv node list`.
  /// Unset: from the environment (securityFromEnvironment()); set: this identity, or no
  /// security when its keystore is empty (tests put secured and unsecured participants in
  /// one process this way).
  std::optional<SecurityIdentity> security;
};

/// The security `options` asks for, resolved (see ParticipantOptions::security).
std::optional<SecurityFiles> participantSecurity(const ParticipantOptions& options);

/// Called from a middleware thread when `reader` has samples. It must only signal or take
/// from `reader`, never destroy it: deleting a reader waits for its running callbacks.
using DataCallback = std::function<void(DataReader& reader)>;

class SerializedWriter;  // auv/interfaces/serialized.h
class SerializedReader;
/// As DataCallback, for a serialized reader.
using SerializedDataCallback = std::function<void(SerializedReader& reader)>;

/// One DDS domain participant of one vendor.
class Participant {
 public:
  virtual ~Participant() = default;
  virtual Vendor vendor() const = 0;
  virtual Guid guid() const = 0;
  /// Creates a writer on `topic`; throws std::runtime_error with the topic name on failure.
  virtual std::unique_ptr<DataWriter> createWriter(const std::string& topic,
                                                   const msg::TypeSupport& type,
                                                   const QosProfile& qos) = 0;
  /// Creates a reader; `on_data` is called from a middleware thread when samples arrive.
  virtual std::unique_ptr<DataReader> createReader(const std::string& topic,
                                                   const msg::TypeSupport& type,
                                                   const QosProfile& qos, DataCallback on_data) = 0;
  /// A writer of CDR bytes of `type` on `topic` (serialized.h). Throws std::runtime_error
  /// when this participant already uses `type` for typed endpoints, and the reverse.
  virtual std::unique_ptr<SerializedWriter> createSerializedWriter(const std::string& topic,
                                                                   const msg::TypeSupport& type,
                                                                   const QosProfile& qos) = 0;
  /// A reader that delivers samples of `type` on `topic` as CDR bytes (serialized.h);
  /// `on_data` as for createReader.
  virtual std::unique_ptr<SerializedReader> createSerializedReader(
      const std::string& topic, const msg::TypeSupport& type, const QosProfile& qos,
      SerializedDataCallback on_data) = 0;
};

/// Creates a participant of `vendor`. Unless the user set the vendor's own configuration
/// (CYCLONEDDS_URI or FASTRTPS_DEFAULT_PROFILES_FILE), it binds to loopback only. With
/// security (participantSecurity()) it authenticates, checks permissions and encrypts.
std::unique_ptr<Participant> createParticipant(Vendor vendor, const ParticipantOptions& options);

/// Topic names are given ROS-style ("/nav/odometry" or "nav/odometry"); DDS sees
/// "nav/odometry". Throws std::invalid_argument for an empty name or invalid characters.
std::string toDdsTopicName(const std::string& topic);

/// The USER_DATA string every participant of this layer advertises:
/// "auv:node=<name>;host=<hostname>;pid=<pid>;vendor=<vendor>".
std::string participantUserData(Vendor vendor, const std::string& node_name);

namespace detail {
std::unique_ptr<Participant> createCycloneParticipant(const ParticipantOptions& options);
std::unique_ptr<Participant> createFastddsParticipant(const ParticipantOptions& options);
}  // namespace detail

}  // namespace auv::interfaces
