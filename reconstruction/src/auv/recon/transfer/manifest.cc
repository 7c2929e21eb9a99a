#include "auv/recon/transfer/manifest.h"

#include <fcntl.h>
#include <unistd.h>

#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace auv::recon::transfer {
namespace {

constexpr char kFormat[] = "auv-recordings-manifest 1";

}  // namespace

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

Manifest::Manifest(fs::path path) : path_(std::move(path)) {
  std::ifstream in(path_);
  if (!in) return;
  try {
    const json document = json::parse(in);
    if (document.value("format", "") != kFormat) {
      throw std::runtime_error("field 'format' is not '" + std::string(kFormat) + "'");
    }
    for (const json& r : document.at("recordings")) {
      ManifestEntry e;
      e.file = r.at("file").get<std::string>();
      e.camera = r.at("camera").get<std::string>();
      e.vehicle = r.value("vehicle", "");
      e.size_bytes = r.at("size_bytes").get<uint64_t>();
      e.sha256 = r.at("sha256").get<std::string>();
      e.sidecar_file = r.value("sidecar_file", "");
      e.sidecar_size_bytes = r.value("sidecar_size_bytes", uint64_t{0});
      e.sidecar_sha256 = r.value("sidecar_sha256", "");
      e.frame_count = r.value("frame_count", uint64_t{0});
      e.start_time_s = r.value("start_time_s", 0.0);
      e.end_time_s = r.value("end_time_s", 0.0);
      e.time_synchronised = r.value("time_synchronised", false);
      e.verified_at = r.value("verified_at", "");
      entries_[e.file] = e;
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path_.string() + ": not a recordings manifest: " + e.what() +
                             " (move it away to pull again)");
  }
}

const ManifestEntry* Manifest::find(const std::string& file) const {
  auto it = entries_.find(file);
  return it == entries_.end() ? nullptr : &it->second;
}

void Manifest::record(ManifestEntry entry) {
  entries_[entry.file] = std::move(entry);
  save();
}

void Manifest::save() const {
  json recordings = json::array();
  for (const auto& [file, e] : entries_) {
    recordings.push_back({{"file", e.file},
                          {"camera", e.camera},
                          {"vehicle", e.vehicle},
                          {"size_bytes", e.size_bytes},
                          {"sha256", e.sha256},
                          {"sidecar_file", e.sidecar_file},
                          {"sidecar_size_bytes", e.sidecar_size_bytes},
                          {"sidecar_sha256", e.sidecar_sha256},
                          {"frame_count", e.frame_count},
                          {"start_time_s", e.start_time_s},
                          {"end_time_s", e.end_time_s},
                          {"time_synchronised", e.time_synchronised},
                          {"verified_at", e.verified_at}});
  }
  const json document = {{"format", kFormat}, {"recordings", recordings}};
  const fs::path temp = path_.string() + ".tmp";
  {
    std::ofstream out(temp, std::ios::trunc);
    out << document.dump(2) << "\n";
    out.flush();
    if (!out) throw std::runtime_error(temp.string() + ": cannot write");
  }
  const int fd = ::open(temp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  std::error_code error;
  fs::rename(temp, path_, error);
  if (error) throw std::runtime_error(path_.string() + ": cannot replace: " + error.message());
}

}  // namespace auv::recon::transfer
