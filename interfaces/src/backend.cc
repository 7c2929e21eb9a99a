#include "auv/interfaces/backend.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

namespace auv::interfaces {

int DataReader::takeBatch(void* scratch, int max, const SampleVisitor& visit) {
  // One sample at a time: a visit that throws leaves the rest untaken in the reader.
  SampleInfo info;
  int taken = 0;
  while (taken < std::min(max, kMaxBatch) && take(scratch, &info)) {
    ++taken;
    visit(scratch, info);
  }
  return taken;
}

std::string toString(Vendor vendor) {
  return vendor == Vendor::CYCLONEDDS ? "cyclonedds" : "fastdds";
}

Vendor vendorFromString(const std::string& name) {
  if (name == "cyclonedds") return Vendor::CYCLONEDDS;
  if (name == "fastdds") return Vendor::FASTDDS;
  throw std::invalid_argument("unknown DDS vendor '" + name + "' (expected cyclonedds or fastdds)");
}

Vendor vendorFromEnvironment() {
  const char* value = std::getenv("AUV_DDS");
  if (value == nullptr || *value == '\0') return Vendor::CYCLONEDDS;
  try {
    return vendorFromString(value);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("AUV_DDS: ") + e.what());
  }
}

int domainFromEnvironment() {
  const char* value = std::getenv("AUV_DOMAIN_ID");
  if (value == nullptr || *value == '\0') return 0;
  char* end = nullptr;
  const long id = std::strtol(value, &end, 10);
  if (*end != '\0' || id < 0 || id > 232)
    throw std::invalid_argument(
        std::string("AUV_DOMAIN_ID: expected an integer in [0, 232], got '") + value + "'");
  return static_cast<int>(id);
}

std::string toString(const Guid& guid) {
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (uint8_t b : guid) {
    out += kHex[b >> 4];
    out += kHex[b & 15];
  }
  return out;
}

std::string toDdsTopicName(const std::string& topic) {
  std::string name = topic;
  while (!name.empty() && name.front() == '/') name.erase(name.begin());
  if (name.empty()) throw std::invalid_argument("empty topic name '" + topic + "'");
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '/')
      throw std::invalid_argument("invalid topic name '" + topic +
                                  "': use letters, digits, '_' and '/'");
  }
  if (name.back() == '/' || name.find("//") != std::string::npos)
    throw std::invalid_argument("invalid topic name '" + topic + "': empty path element");
  return name;
}

std::string participantUserData(Vendor vendor, const std::string& node_name) {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return "auv:node=" + node_name + ";host=" + host + ";pid=" + std::to_string(getpid()) +
         ";vendor=" + toString(vendor);
}

SecurityFiles securityFiles(const std::string& keystore, const std::string& identity) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path root = fs::absolute(keystore, ec);  // file: URIs must not depend on the cwd
  if (ec) root = keystore;
  root = root.lexically_normal();
  const fs::path id = root / "identities" / identity;
  SecurityFiles files;
  files.identity_ca = (root / "ca.cert.pem").string();
  files.permissions_ca = files.identity_ca;
  files.governance = (root / "governance.p7s").string();
  files.certificate = (id / "cert.pem").string();
  files.private_key = (id / "key.pem").string();
  files.permissions = (id / "permissions.p7s").string();
  return files;
}

std::optional<SecurityIdentity> securityFromEnvironment() {
  const auto get = [](const char* name) {
    const char* value = std::getenv(name);
    return std::string(value != nullptr ? value : "");
  };
  SecurityIdentity security;
  security.keystore = get("AUV_SECURITY_KEYSTORE");
  if (security.keystore.empty()) return std::nullopt;
  security.identity = get("AUV_SECURITY_IDENTITY");
  if (security.identity.empty() || security.identity.find('/') != std::string::npos)
    throw std::invalid_argument(
        "AUV_SECURITY_IDENTITY: AUV_SECURITY_KEYSTORE is set, so name the identity this "
        "process uses (a folder under " +
        security.keystore + "/identities/), got '" + security.identity + "'");
  const std::string strategy = get("AUV_SECURITY_STRATEGY");
  if (strategy == "Permissive") {
    security.enforce = false;
  } else if (!strategy.empty() && strategy != "Enforce") {
    throw std::invalid_argument("AUV_SECURITY_STRATEGY: expected Enforce or Permissive, got '" +
                                strategy + "'");
  }
  return security;
}

std::optional<SecurityFiles> resolveSecurity(const SecurityIdentity& security) {
  if (security.keystore.empty()) return std::nullopt;
  const SecurityFiles files = securityFiles(security.keystore, security.identity);
  for (const std::string* file : {&files.identity_ca, &files.governance, &files.certificate,
                                  &files.private_key, &files.permissions}) {
    // Both vendors report an unreadable file only as a failed participant: name it here.
    if (std::ifstream(*file).good()) continue;
    const std::string problem = "DDS Security: cannot read " + *file + " (identity '" +
                                security.identity + "' of keystore " + security.keystore + ")";
    if (security.enforce)
      throw std::runtime_error(problem +
                               "; create it with `auv security init`, or set "
                               "AUV_SECURITY_STRATEGY=Permissive to run unsecured");
    std::cerr << "warning: " << problem << ": running UNSECURED (AUV_SECURITY_STRATEGY="
              << "Permissive)\n";
    return std::nullopt;
  }
  return files;
}

std::optional<SecurityFiles> participantSecurity(const ParticipantOptions& options) {
  if (options.security) return resolveSecurity(*options.security);
  const std::optional<SecurityIdentity> from_environment = securityFromEnvironment();
  if (!from_environment) return std::nullopt;
  return resolveSecurity(*from_environment);
}

std::unique_ptr<Participant> createParticipant(Vendor vendor, const ParticipantOptions& options) {
  return vendor == Vendor::CYCLONEDDS ? detail::createCycloneParticipant(options)
                                      : detail::createFastddsParticipant(options);
}

}  // namespace auv::interfaces
