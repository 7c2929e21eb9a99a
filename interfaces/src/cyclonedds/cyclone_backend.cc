// Cyclone DDS backend: plain C API plus the custom sertype of cyclone_sertype.cc.
#include <dds/dds.h>
#include <dlfcn.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "auv/interfaces/backend.h"
#include "cyclone_config.h"
#include "cyclone_sertype.h"
#include "serialized_sample.h"

namespace auv::interfaces::detail {
namespace {

// Binds Cyclone to loopback unless the user configured it (CYCLONEDDS_URI). Multicast is
// forced on `lo` so discovery works without peers lists (docs/library-notes.md). The receive buffer
// asks for 4 MiB (Cyclone's default asks 1 MiB) so a burst of fragments of a large sample
// is not dropped and repaired a heartbeat later; the kernel caps it at net.core.rmem_max,
// and min="default" accepts whatever is granted (a `min` above rmem_max would make Cyclone
// refuse to start). Measured in docs/performance.md.
constexpr const char* kLoopbackConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces>"
    "<NetworkInterface name=\"lo\" multicast=\"true\"/>"
    "</Interfaces><AllowMulticast>true</AllowMulticast></General>"
    "<Internal><SocketReceiveBufferSize min=\"default\" max=\"4MB\"/></Internal>"
    "%SECURITY%</Domain></CycloneDDS>";

// Debian installs the security plugins in a folder beside libddsc (libddsc0debian/), which
// dlopen does not search; upstream builds put them next to libddsc, where the plain name
// works. `name` is e.g. "dds_security_auth".
std::string securityLibrary(const std::string& name) {
  namespace fs = std::filesystem;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &info) == 0 ||
      info.dli_fname == nullptr)
    return name;
  std::error_code ec;
  const fs::path dir = fs::path(info.dli_fname).parent_path();
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().filename().string().rfind("libddsc", 0) != 0) continue;
    const fs::path candidate = entry.path() / ("lib" + name + ".so");
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  return name;
}

// The three plugins and the six files, as the dds.sec.* properties the OMG specification
// names (Cyclone reads the same names from the participant QoS).
std::vector<std::pair<std::string, std::string>> securityProperties(const SecurityFiles& files) {
  const std::string auth = securityLibrary("dds_security_auth");
  const std::string access = securityLibrary("dds_security_ac");
  const std::string crypto = securityLibrary("dds_security_crypto");
  return {
      {"dds.sec.auth.library.path", auth},
      {"dds.sec.auth.library.init", "init_authentication"},
      {"dds.sec.auth.library.finalize", "finalize_authentication"},
      {"dds.sec.auth.identity_ca", "file:" + files.identity_ca},
      {"dds.sec.auth.identity_certificate", "file:" + files.certificate},
      {"dds.sec.auth.private_key", "file:" + files.private_key},
      {"dds.sec.access.library.path", access},
      {"dds.sec.access.library.init", "init_access_control"},
      {"dds.sec.access.library.finalize", "finalize_access_control"},
      {"dds.sec.access.permissions_ca", "file:" + files.permissions_ca},
      {"dds.sec.access.governance", "file:" + files.governance},
      {"dds.sec.access.permissions", "file:" + files.permissions},
      {"dds.sec.crypto.library.path", crypto},
      {"dds.sec.crypto.library.init", "init_crypto"},
      {"dds.sec.crypto.library.finalize", "finalize_crypto"},
  };
}

// The same as a <Security> element of the domain configuration: participants created
// without dds.sec.* properties in their QoS (the graph inspector's) take it from there.
std::string securityConfigXml(const SecurityFiles& files) {
  const auto library = [](const std::string& path, const char* init, const char* finalize) {
    return "<Library path=\"" + path + "\" initFunction=\"" + init + "\" finalizeFunction=\"" +
           finalize + "\"/>";
  };
  return "<Security><Authentication>" +
         library(securityLibrary("dds_security_auth"), "init_authentication",
                 "finalize_authentication") +
         "<IdentityCA>file:" + files.identity_ca +
         "</IdentityCA><IdentityCertificate>file:" + files.certificate +
         "</IdentityCertificate><PrivateKey>file:" + files.private_key +
         "</PrivateKey></Authentication><AccessControl>" +
         library(securityLibrary("dds_security_ac"), "init_access_control",
                 "finalize_access_control") +
         "<PermissionsCA>file:" + files.permissions_ca +
         "</PermissionsCA><Governance>file:" + files.governance +
         "</Governance><Permissions>file:" + files.permissions +
         "</Permissions></AccessControl><Cryptographic>" +
         library(securityLibrary("dds_security_crypto"), "init_crypto", "finalize_crypto") +
         "</Cryptographic></Security>";
}

void check(dds_return_t rc, const std::string& what) {
  if (rc < 0) throw std::runtime_error("cyclonedds: " + what + ": " + dds_strretcode(rc));
}

}  // namespace

// One explicitly created domain per domain id and process, kept for the process lifetime.
void ensureCycloneDomain(int domain_id) {
  static std::mutex mutex;
  static std::map<int, dds_entity_t> domains;
  const char* uri = std::getenv("CYCLONEDDS_URI");
  if (uri != nullptr && *uri != '\0') return;  // Cyclone reads the user's configuration itself
  std::lock_guard<std::mutex> lock(mutex);
  if (domains.count(domain_id)) return;
  std::string config = kLoopbackConfig;
  std::string security;
  if (const std::optional<SecurityIdentity> identity = securityFromEnvironment()) {
    if (const std::optional<SecurityFiles> files = resolveSecurity(*identity))
      security = securityConfigXml(*files);
  }
  config.replace(config.find("%SECURITY%"), 10, security);
  const dds_entity_t domain =
      dds_create_domain(static_cast<dds_domainid_t>(domain_id), config.c_str());
  if (domain < 0 && domain != DDS_RETCODE_PRECONDITION_NOT_MET)
    check(domain, "create domain " + std::to_string(domain_id));
  domains[domain_id] = domain;
}

namespace {

dds_duration_t toDuration(double seconds) {
  return seconds <= 0 ? DDS_INFINITY : static_cast<dds_duration_t>(seconds * 1e9);
}

struct QosDeleter {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

QosPtr toCycloneQos(const QosProfile& p) {
  QosPtr q(dds_create_qos());
  dds_qset_reliability(q.get(),
                       p.reliability == Reliability::RELIABLE ? DDS_RELIABILITY_RELIABLE
                                                              : DDS_RELIABILITY_BEST_EFFORT,
                       toDuration(p.max_blocking_time_s));
  dds_qset_durability(q.get(), p.durability == Durability::TRANSIENT_LOCAL
                                   ? DDS_DURABILITY_TRANSIENT_LOCAL
                                   : DDS_DURABILITY_VOLATILE);
  const dds_history_kind_t history =
      p.history == History::KEEP_LAST ? DDS_HISTORY_KEEP_LAST : DDS_HISTORY_KEEP_ALL;
  dds_qset_history(q.get(), history, p.depth);
  if (p.durability == Durability::TRANSIENT_LOCAL) {
    // Without this Cyclone keeps only one historical sample per writer (docs/library-notes.md).
    dds_qset_durability_service(q.get(), 0, history, p.depth, p.max_samples, p.max_instances,
                                p.max_samples_per_instance);
  }
  dds_qset_deadline(q.get(), toDuration(p.deadline_s));
  dds_qset_liveliness(q.get(),
                      p.liveliness == Liveliness::AUTOMATIC ? DDS_LIVELINESS_AUTOMATIC
                                                            : DDS_LIVELINESS_MANUAL_BY_TOPIC,
                      toDuration(p.liveliness_lease_s));
  dds_qset_resource_limits(q.get(), p.max_samples, p.max_instances, p.max_samples_per_instance);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q.get(), 1, &xcdr1);
  return q;
}

Guid guidOf(dds_entity_t entity) {
  dds_guid_t g;
  check(dds_get_guid(entity, &g), "get guid");
  Guid guid;
  std::memcpy(guid.data(), g.v, 16);
  return guid;
}

class CycloneWriter : public DataWriter {
 public:
  explicit CycloneWriter(dds_entity_t writer) : writer_(writer) {}
  ~CycloneWriter() override { dds_delete(writer_); }
  void write(const void* sample) override { check(dds_write(writer_, sample), "write"); }
  int matchedReaders() const override {
    dds_publication_matched_status_t status;
    return dds_get_publication_matched_status(writer_, &status) == 0
               ? static_cast<int>(status.current_count)
               : 0;
  }
  bool waitForAcknowledgments(double timeout_s) override {
    return dds_wait_for_acks(writer_, static_cast<dds_duration_t>(timeout_s * 1e9)) == 0;
  }
  Guid guid() const override { return guidOf(writer_); }

 private:
  dds_entity_t writer_;
};

class CycloneReader : public DataReader {
 public:
  explicit CycloneReader(DataCallback on_data) : on_data_(std::move(on_data)) {}
  ~CycloneReader() override {
    if (reader_ > 0) dds_delete(reader_);
  }
  void attach(dds_entity_t reader) { reader_ = reader; }
  bool take(void* sample, SampleInfo* info) override {
    for (;;) {
      void* buffers[1] = {sample};
      dds_sample_info_t si;
      takeFailed();  // a stale flag must not drop a good sample
      const dds_return_t n = dds_take(reader_, buffers, &si, 1, 1);
      if (n <= 0) return false;
      if (!si.valid_data) continue;  // dispose/unregister notifications carry no data
      if (takeFailed()) continue;    // malformed: taken out, not handed on half-filled
      if (info != nullptr) {
        info->source_timestamp_ns = si.source_timestamp;
        info->publication = publicationGuid(si.publication_handle);
      }
      return true;
    }
  }
  int matchedWriters() const override {
    dds_subscription_matched_status_t status;
    return dds_get_subscription_matched_status(reader_, &status) == 0
               ? static_cast<int>(status.current_count)
               : 0;
  }
  Guid guid() const override { return guidOf(reader_); }
  // The writer's GUID for a publication handle. Cached: the lookup copies the writer's whole
  // discovery data (two thirds of the take path, docs/performance.md).
  Guid publicationGuid(dds_instance_handle_t handle) {
    auto it = publication_guids_.find(handle);
    if (it != publication_guids_.end()) return it->second;
    Guid guid{};
    if (dds_builtintopic_endpoint_t* pub = dds_get_matched_publication_data(reader_, handle)) {
      std::memcpy(guid.data(), pub->key.v, 16);
      dds_builtintopic_free_endpoint(pub);
      publication_guids_[handle] = guid;
    }
    return guid;
  }
  static void onDataAvailable(dds_entity_t reader, void* arg) {
    auto* self = static_cast<CycloneReader*>(arg);
    // Cyclone may call this before dds_create_reader returns (history of a local writer):
    // take() then needs the handle already. Same value as attach() stores.
    if (self->reader_.load(std::memory_order_relaxed) <= 0) self->reader_ = reader;
    if (self->on_data_) self->on_data_(*self);
  }

 private:
  DataCallback on_data_;
  std::map<dds_instance_handle_t, Guid> publication_guids_;  // take() is called by one thread
  std::atomic<dds_entity_t> reader_{0};
};

class CycloneParticipant : public Participant {
 public:
  explicit CycloneParticipant(const ParticipantOptions& options) {
    ensureCycloneDomain(options.domain_id);
    QosPtr q(dds_create_qos());
    const std::string user_data = participantUserData(Vendor::CYCLONEDDS, options.node_name);
    dds_qset_userdata(q.get(), user_data.data(), user_data.size());
    dds_qset_entity_name(q.get(), options.node_name.c_str());
    const std::optional<SecurityFiles> security = participantSecurity(options);
    if (security) {
      for (const auto& [name, value] : securityProperties(*security))
        dds_qset_prop(q.get(), name.c_str(), value.c_str());
    }
    participant_ =
        dds_create_participant(static_cast<dds_domainid_t>(options.domain_id), q.get(), nullptr);
    check(participant_, "create participant on domain " + std::to_string(options.domain_id) +
                            (security ? " with DDS Security (certificate " + security->certificate +
                                            ", governance or permissions rejected; Cyclone logs "
                                            "why when CYCLONEDDS_URI enables tracing)"
                                      : std::string()));
  }
  ~CycloneParticipant() override { dds_delete(participant_); }

  Vendor vendor() const override { return Vendor::CYCLONEDDS; }
  Guid guid() const override { return guidOf(participant_); }

  std::unique_ptr<DataWriter> createWriter(const std::string& topic, const msg::TypeSupport& type,
                                           const QosProfile& qos) override {
    return makeWriter(topic, type, qos, false);
  }

  std::unique_ptr<DataReader> createReader(const std::string& topic, const msg::TypeSupport& type,
                                           const QosProfile& qos, DataCallback on_data) override {
    return makeReader(topic, type, qos, std::move(on_data), false);
  }

  std::unique_ptr<SerializedWriter> createSerializedWriter(const std::string& topic,
                                                           const msg::TypeSupport& type,
                                                           const QosProfile& qos) override {
    return makeSerializedWriter(makeWriter(topic, type, qos, true), type);
  }

  std::unique_ptr<SerializedReader> createSerializedReader(
      const std::string& topic, const msg::TypeSupport& type, const QosProfile& qos,
      SerializedDataCallback on_data) override {
    auto adapter = std::make_unique<SerializedReaderAdapter>(std::move(on_data));
    adapter->attach(makeReader(topic, type, qos, adapter->dataCallback(), true));
    return adapter;
  }

 private:
  // `serialized`: over the serialized sertype, moving RawSamples (serialized_sample.h).
  std::unique_ptr<DataWriter> makeWriter(const std::string& topic, const msg::TypeSupport& type,
                                         const QosProfile& qos, bool serialized) {
    const dds_entity_t t = createTopic(topic, type, serialized);
    QosPtr q = toCycloneQos(qos);
    const dds_entity_t w = dds_create_writer(participant_, t, q.get(), nullptr);
    check(w, "create writer on '" + topic + "'");
    return std::make_unique<CycloneWriter>(w);
  }

  std::unique_ptr<DataReader> makeReader(const std::string& topic, const msg::TypeSupport& type,
                                         const QosProfile& qos, DataCallback on_data,
                                         bool serialized) {
    const dds_entity_t t = createTopic(topic, type, serialized);
    QosPtr q = toCycloneQos(qos);
    auto reader = std::make_unique<CycloneReader>(std::move(on_data));
    dds_listener_t* listener = dds_create_listener(reader.get());
    dds_lset_data_available(listener, &CycloneReader::onDataAvailable);
    const dds_entity_t r = dds_create_reader(participant_, t, q.get(), listener);
    dds_delete_listener(listener);
    check(r, "create reader on '" + topic + "'");
    reader->attach(r);
    return reader;
  }

  dds_entity_t createTopic(const std::string& topic, const msg::TypeSupport& type,
                           bool serialized) {
    const std::string name = toDdsTopicName(topic);
    std::lock_guard<std::mutex> lock(mutex_);
    // Typed or serialized per type name, as Fast DDS requires: the same rule on both vendors.
    const auto kind = serialized_types_.emplace(type.name, serialized).first;
    if (kind->second != serialized)
      throw std::runtime_error("cyclonedds: type " + type.name + " is used by " +
                               (kind->second ? "serialized" : "typed") +
                               " endpoints of this participant; " +
                               (serialized ? "serialized" : "typed") +
                               " endpoints of it need a participant of their own");
    auto it = topics_.find(name);
    if (it != topics_.end()) {
      if (it->second.second != type.name)
        throw std::runtime_error("topic '" + topic + "' already has type " + it->second.second +
                                 ", not " + type.name);
      return it->second.first;
    }
    ddsi_sertype* sertype = createSertype(type, serialized);
    const dds_entity_t t =
        dds_create_topic_sertype(participant_, name.c_str(), &sertype, nullptr, nullptr, nullptr);
    check(t, "create topic '" + topic + "' of type " + type.name);
    topics_[name] = {t, type.name};
    return t;
  }

  dds_entity_t participant_;
  std::mutex mutex_;
  std::map<std::string, std::pair<dds_entity_t, std::string>> topics_;
  std::map<std::string, bool> serialized_types_;  // type name -> used by serialized endpoints
};

}  // namespace

std::unique_ptr<Participant> createCycloneParticipant(const ParticipantOptions& options) {
  return std::make_unique<CycloneParticipant>(options);
}

}  // namespace auv::interfaces::detail
