#include "security/keystore.h"

#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "auv/config/yaml_scalars.h"
#include "auv/interfaces/backend.h"
#include "security/openssl_util.h"

namespace auv::bringup {
namespace {

namespace fs = std::filesystem;

// Files of the keystore outside the identities (the backend owns the identity layout).
constexpr const char* kCaCertificate = "ca.cert.pem";
constexpr const char* kCaKey = "private/ca.key.pem";
constexpr const char* kGovernance = "governance.p7s";
constexpr const char* kGovernanceXml = "governance.xml";
constexpr const char* kSettings = "keystore.yaml";

// keystore.yaml through config::loadYaml, as every reader of a file a user can edit: an alias
// cycle or an alias bomb is a YAML::ParserException, not an endless walk.
YAML::Node readSettings(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw YAML::BadFile(file.string());
  std::ostringstream text;
  text << in.rdbuf();
  return config::loadYaml(text.str());
}
constexpr const char* kCaName = "auv-inspect CA";

bool validIdentityName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  }
  return true;
}

// "YYYY-MM-DDTHH:MM:SS" (UTC) `offset_s` from now: the xs:dateTime of permissions validity.
std::string xmlDate(long offset_s) {
  const std::time_t t = std::time(nullptr) + offset_s;
  std::tm utc{};
  gmtime_r(&t, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%S", &utc);
  return buffer;
}

// Cyclone's governance/permissions parser rejects domain ids above 230 (DDS ids 231 and 232
// cannot be secured with it).
constexpr int kMaxSecuredDomain = 230;

std::string domainsXml(int domain_id) {
  if (domain_id >= 0) return "<domains><id>" + std::to_string(domain_id) + "</id></domains>";
  return "<domains><id_range><min>0</min><max>" + std::to_string(kMaxSecuredDomain) +
         "</max></id_range></domains>";
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

void makeDirectory(const fs::path& path, fs::perms perms) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) throw std::runtime_error("cannot create " + path.string() + ": " + ec.message());
  fs::permissions(path, perms, ec);
}

// Writes identities/<name>/ with a key, a certificate signed by the CA and signed permissions.
void writeIdentity(const fs::path& root, const std::string& name, long serial, X509* ca,
                   EVP_PKEY* ca_key, const KeystoreOptions& options) {
  const interfaces::SecurityFiles files = interfaces::securityFiles(root.string(), name);
  makeDirectory(fs::path(files.certificate).parent_path(),
                fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
  PkeyPtr key = generateEcKey();
  CertificateOptions cert_options;
  cert_options.common_name = name;
  cert_options.organization = options.organization;
  cert_options.valid_days = options.valid_days;
  cert_options.serial = serial;
  X509Ptr cert = makeCertificate(cert_options, key.get(), ca, ca_key);
  writePrivateKey(files.private_key, key.get());
  writeCertificate(files.certificate, cert.get());
  const std::string permissions = permissionsXml(name, subjectName(cert.get()), xmlDate(-3600),
                                                 xmlDate(86400L * options.valid_days), options);
  writeText(fs::path(files.permissions).replace_extension(".xml"), permissions);
  writeSignedDocument(files.permissions, permissions, ca, ca_key);
}

void checkOptions(const KeystoreOptions& options) {
  const std::string problem = options.check();
  if (!problem.empty()) throw std::runtime_error(problem);
}

}  // namespace

std::string KeystoreOptions::check() const {
  if (identities.empty()) return "identities: give at least one identity";
  for (size_t i = 0; i < identities.size(); ++i) {
    if (!validIdentityName(identities[i]))
      return "identities: '" + identities[i] +
             "' is not a valid identity name (1-64 letters, digits, '_' or '-')";
    for (size_t j = 0; j < i; ++j) {
      if (identities[j] == identities[i])
        return "identities: '" + identities[i] + "' is given twice";
    }
  }
  if (domain_id < -1 || domain_id > kMaxSecuredDomain)
    return "domain: expected a DDS domain id in [0, " + std::to_string(kMaxSecuredDomain) +
           "] (Cyclone secures no higher id), got " + std::to_string(domain_id);
  if (valid_days < 1 || valid_days > 36500)
    return "days: expected 1-36500, got " + std::to_string(valid_days);
  if (organization.empty() || organization.find_first_of(",=+<>#;\"\\") != std::string::npos)
    return "organization: '" + organization + "' must be non-empty, without , = + < > # ; \" \\";
  return "";
}

std::string governanceXml(const KeystoreOptions& options) {
  // Every topic: only authenticated participants join, read and write need permission, data
  // and submessages are encrypted; discovery and liveliness go over the secure built-in
  // endpoints, encrypted. RTPS-message protection is left off: every submessage already is.
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )" +
         domainsXml(options.domain_id) +
         R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string permissionsXml(const std::string& identity, const std::string& subject,
                           const std::string& not_before, const std::string& not_after,
                           const KeystoreOptions& options) {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         identity + R"(">
      <subject_name>)" +
         subject + R"(</subject_name>
      <validity>
        <not_before>)" +
         not_before + R"(</not_before>
        <not_after>)" +
         not_after + R"(</not_after>
      </validity>
      <allow_rule>
        )" +
         domainsXml(options.domain_id) +
         R"(
        <publish><topics><topic>*</topic></topics></publish>
        <subscribe><topics><topic>*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

void createKeystore(const std::string& folder, const KeystoreOptions& options) {
  checkOptions(options);
  const fs::path target = fs::absolute(folder).lexically_normal();
  std::error_code ec;
  const bool exists = fs::exists(target, ec);
  if (exists && !fs::is_directory(target, ec))
    throw std::runtime_error(target.string() + " exists and is not a folder");
  if (exists && !fs::is_empty(target, ec)) {
    if (!fs::exists(target / kCaCertificate, ec))
      throw std::runtime_error(target.string() +
                               " is a non-empty folder that is not a keystore: refusing to "
                               "write into it");
    if (!options.force)
      throw std::runtime_error(target.string() +
                               " already holds a keystore: refusing to overwrite it (--force "
                               "replaces it; every identity then needs the new files)");
  }
  // Build beside the target and rename at the end: a failure never leaves half a keystore,
  // and a forced replacement never destroys the old one before the new one is complete.
  const fs::path parent = target.parent_path();
  makeDirectory(parent, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                            fs::perms::others_read | fs::perms::others_exec);
  const std::string suffix = std::to_string(::getpid());
  const fs::path staging = parent / ("." + target.filename().string() + ".new-" + suffix);
  fs::remove_all(staging, ec);
  try {
    makeDirectory(staging, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
    makeDirectory(staging / "private", fs::perms::owner_all);
    PkeyPtr ca_key = generateEcKey();
    CertificateOptions ca_options;
    ca_options.common_name = kCaName;
    ca_options.organization = options.organization;
    ca_options.valid_days = options.valid_days;
    ca_options.certificate_authority = true;
    X509Ptr ca = makeCertificate(ca_options, ca_key.get(), nullptr, nullptr);
    writePrivateKey((staging / kCaKey).string(), ca_key.get());
    writeCertificate((staging / kCaCertificate).string(), ca.get());
    const std::string governance = governanceXml(options);
    writeText(staging / kGovernanceXml, governance);
    writeSignedDocument((staging / kGovernance).string(), governance, ca.get(), ca_key.get());
    long serial = 2;  // 1 is the CA's
    for (const std::string& name : options.identities)
      writeIdentity(staging, name, serial++, ca.get(), ca_key.get(), options);
    YAML::Emitter settings;
    settings << YAML::BeginMap << YAML::Key << "organization" << YAML::Value << options.organization
             << YAML::Key << "domain_id" << YAML::Value << options.domain_id << YAML::Key
             << "next_serial" << YAML::Value << serial << YAML::EndMap;
    writeText(staging / kSettings, std::string(settings.c_str()) + "\n");
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  const fs::path old = parent / ("." + target.filename().string() + ".old-" + suffix);
  if (exists) fs::rename(target, old);
  fs::rename(staging, target, ec);
  if (ec) {
    if (exists) fs::rename(old, target);
    fs::remove_all(staging);
    throw std::runtime_error("cannot move the new keystore to " + target.string() + ": " +
                             ec.message());
  }
  if (exists) fs::remove_all(old, ec);
}

void addIdentity(const std::string& folder, const std::string& identity,
                 const KeystoreOptions& options) {
  const fs::path root = fs::absolute(folder).lexically_normal();
  if (!fs::exists(root / kSettings))
    throw std::runtime_error(root.string() + " is not a keystore (no " + kSettings + ")");
  KeystoreOptions settings = options;
  settings.identities = {identity};
  long serial = 0;
  try {
    const YAML::Node node = readSettings(root / kSettings);
    settings.organization = node["organization"].as<std::string>();
    settings.domain_id = node["domain_id"].as<int>();
    serial = node["next_serial"].as<long>();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error((root / kSettings).string() + ": " + e.what());
  }
  checkOptions(settings);
  const interfaces::SecurityFiles files = interfaces::securityFiles(root.string(), identity);
  if (fs::exists(files.certificate) && !options.force)
    throw std::runtime_error("identity '" + identity + "' already exists in " + root.string() +
                             " (--force replaces it)");
  X509Ptr ca = readCertificate((root / kCaCertificate).string());
  PkeyPtr ca_key = readPrivateKey((root / kCaKey).string());
  writeIdentity(root, identity, serial, ca.get(), ca_key.get(), settings);
  YAML::Node node = readSettings(root / kSettings);
  node["next_serial"] = serial + 1;
  YAML::Emitter out;
  out << node;
  writeText(root / kSettings, std::string(out.c_str()) + "\n");
}

std::string crossVendorProblem(const std::string& organization,
                               const std::vector<std::string>& cyclonedds,
                               const std::vector<std::string>& fastdds) {
  std::string problem;
  for (const std::string& cyclone : cyclonedds) {
    for (const std::string& fast : fastdds) {
      const uint64_t cyclone_rank = handshakeRank(cyclone, organization);
      const uint64_t fast_rank = handshakeRank(fast, organization);
      if (cyclone_rank < fast_rank) continue;
      problem += "Cyclone DDS identity '" + cyclone + "' cannot authenticate with Fast DDS " +
                 "identity '" + fast + "': " +
                 (cyclone == fast ? std::string("the same identity on both vendors")
                                  : "the Fast DDS side would start the handshake") +
                 ", which Cyclone DDS 0.10 cannot answer.";
      // Suggest the first variant of the name that ranks below the Fast DDS identity.
      for (int i = 1; i < 1000; ++i) {
        const std::string candidate = cyclone + "-" + std::to_string(i);
        if (handshakeRank(candidate, organization) < fast_rank) {
          problem += " An identity named '" + candidate + "' would work with it.";
          break;
        }
      }
      problem += "\n";
    }
  }
  return problem;
}

std::string keystoreOrganization(const std::string& folder) {
  const fs::path settings = fs::absolute(folder).lexically_normal() / kSettings;
  try {
    return readSettings(settings)["organization"].as<std::string>();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(settings.string() + ": " + e.what());
  }
}

std::vector<IdentityInfo> listKeystore(const std::string& folder, std::string* ca_expiry) {
  const fs::path root = fs::absolute(folder).lexically_normal();
  if (!fs::exists(root / kCaCertificate))
    throw std::runtime_error(root.string() + " is not a keystore (no " + kCaCertificate + ")");
  X509Ptr ca = readCertificate((root / kCaCertificate).string());
  if (ca_expiry != nullptr) *ca_expiry = notAfter(ca.get());
  std::vector<IdentityInfo> identities;
  std::error_code ec;
  std::vector<fs::path> folders;
  for (const auto& entry : fs::directory_iterator(root / "identities", ec)) {
    if (entry.is_directory()) folders.push_back(entry.path());
  }
  std::sort(folders.begin(), folders.end());
  for (const fs::path& path : folders) {
    IdentityInfo info;
    info.name = path.filename().string();
    const interfaces::SecurityFiles files = interfaces::securityFiles(root.string(), info.name);
    try {
      X509Ptr cert = readCertificate(files.certificate);
      info.subject = subjectName(cert.get());
      info.certificate_expiry = notAfter(cert.get());
      X509_STORE* store = X509_STORE_new();
      X509_STORE_add_cert(store, ca.get());
      X509_STORE_CTX* ctx = X509_STORE_CTX_new();
      X509_STORE_CTX_init(ctx, store, cert.get(), nullptr);
      const bool valid = X509_verify_cert(ctx) == 1;
      const std::string reason =
          valid ? "" : X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx));
      X509_STORE_CTX_free(ctx);
      X509_STORE_free(store);
      if (!valid) throw std::runtime_error(files.certificate + ": " + reason);
      readPrivateKey(files.private_key);
      verifySignedDocument(files.permissions, ca.get());
    } catch (const std::exception& e) {
      info.problem = e.what();
    }
    identities.push_back(info);
  }
  return identities;
}

}  // namespace auv::bringup
