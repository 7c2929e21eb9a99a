#include "auv/interfaces/backend.h"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace auv::interfaces {

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

std::unique_ptr<Participant> createParticipant(Vendor vendor, const ParticipantOptions& options) {
  return vendor == Vendor::CYCLONEDDS ? detail::createCycloneParticipant(options)
                                      : detail::createFastddsParticipant(options);
}

}  // namespace auv::interfaces
