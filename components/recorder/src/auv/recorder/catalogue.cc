#include "auv/recorder/catalogue.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "auv/transfer/sha256.h"

namespace fs = std::filesystem;

namespace auv::recorder {
namespace {

constexpr char kIncomplete[] = ".incomplete";
constexpr char kSidecarSuffix[] = ".frames.csv";
constexpr size_t kMaxKeyBytes = 255;  // @key strings of RecordingInfo (idl/README.md)

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string withoutSuffix(const std::string& text, const std::string& suffix) {
  return text.substr(0, text.size() - suffix.size());
}

/// The metadata fields a client sees (what a change must be published for).
auto visibleFields(const Recording& r) {
  return std::tie(r.camera_id, r.file_path, r.sidecar_file, r.size_bytes, r.sha256, r.start_time_s,
                  r.end_time_s, r.frame_count, r.sidecar_size_bytes, r.sidecar_sha256, r.complete,
                  r.problem, r.disk_path, r.sidecar_disk_path);
}

std::string shortDigest(const std::string& sha) { return sha.substr(0, 12); }

// The recording `file_path` names: itself, or the recording of a sidecar's name.
template <class Recordings>
auto findRecordingOf(Recordings& recordings, const std::string& file_path) {
  auto it = recordings.find(file_path);
  if (it == recordings.end() && endsWith(file_path, kSidecarSuffix)) {
    it = recordings.find(withoutSuffix(file_path, kSidecarSuffix));
  }
  return it;
}

}  // namespace

void CatalogueOptions::check() const {
  if (root.empty()) throw std::invalid_argument("root: empty (the recordings folder)");
  if (extensions.empty()) throw std::invalid_argument("extensions: empty list");
  for (const auto& extension : extensions) {
    if (extension.size() < 2 || extension.front() != '.' ||
        extension.find('/') != std::string::npos) {
      throw std::invalid_argument("extensions: '" + extension +
                                  "' is not a file ending like '.mp4'");
    }
  }
}

SidecarSummary readSidecarSummary(const fs::path& path, bool partial) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  if (partial) {
    // A writer may be half-way through a line: only terminated lines count.
    const size_t last_newline = text.rfind('\n');
    text.resize(last_newline == std::string::npos ? 0 : last_newline + 1);
    if (text.empty()) return {};
  }
  std::istringstream lines(text);
  std::string line;
  if (!std::getline(lines, line)) throw std::runtime_error(path.string() + ": empty, no header");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::vector<std::string> header;
  {
    std::istringstream columns(line);
    std::string column;
    while (std::getline(columns, column, ',')) header.push_back(column);
  }
  const auto time_column = std::find(header.begin(), header.end(), "camera_time_s");
  if (header.empty() || header.front() != "frame" || time_column == header.end()) {
    throw std::runtime_error(path.string() + " line 1: header '" + line +
                             "' does not start with frame and name camera_time_s");
  }
  const size_t time_index = static_cast<size_t>(time_column - header.begin());
  SidecarSummary summary;
  size_t line_number = 1;
  while (std::getline(lines, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::istringstream columns(line);
    std::string field;
    while (std::getline(columns, field, ',')) fields.push_back(field);
    if (fields.size() <= time_index) {
      throw std::runtime_error(path.string() + " line " + std::to_string(line_number) + ": " +
                               std::to_string(fields.size()) + " fields, camera_time_s missing");
    }
    char* end = nullptr;
    const double t = std::strtod(fields[time_index].c_str(), &end);
    if (end == fields[time_index].c_str() || *end != '\0' || !std::isfinite(t)) {
      throw std::runtime_error(path.string() + " line " + std::to_string(line_number) +
                               ": camera_time_s '" + fields[time_index] + "' is not a number");
    }
    if (summary.frames == 0) summary.first_camera_time_s = t;
    summary.last_camera_time_s = t;
    ++summary.frames;
  }
  return summary;
}

Catalogue::Catalogue(CatalogueOptions options) : options_(std::move(options)) { options_.check(); }

std::map<std::string, Catalogue::Found> Catalogue::walk(ScanReport& report) const {
  std::map<std::string, Found> found;
  std::vector<std::string> cameras;
  std::error_code error;
  fs::directory_iterator cameras_it(options_.root, error);
  if (error) return found;  // no root (yet): an empty catalogue
  struct Sidecar {
    std::string disk_path;
    bool closed;
  };
  std::map<std::string, Sidecar> sidecars;  // by the final recording name
  for (const auto& camera_entry : cameras_it) {
    const std::string camera = camera_entry.path().filename().string();
    // Only real folders: a symlink could lead out of the root.
    if (camera.empty() || camera.front() == '.' || !camera_entry.is_directory(error) ||
        camera_entry.is_symlink(error)) {
      continue;
    }
    if (camera.size() > kMaxKeyBytes) {
      report.messages.push_back("skipped camera folder '" + camera + "': name over 255 bytes");
      continue;
    }
    cameras.push_back(camera);
    fs::directory_iterator files(camera_entry.path(), error);
    if (error) {
      report.messages.push_back(camera_entry.path().string() + ": " + error.message());
      continue;
    }
    for (const auto& file_entry : files) {
      const std::string name = file_entry.path().filename().string();
      const std::string relative = camera + "/" + name;
      const auto stamp = stampOf(file_entry.path());  // regular files only, no symlinks
      if (!stamp || name.front() == '.') continue;
      for (const auto& extension : options_.extensions) {
        const std::string open_video = std::string(kIncomplete) + extension;
        const std::string closed_sidecar = extension + kSidecarSuffix;
        const std::string open_sidecar = closed_sidecar + kIncomplete;
        std::string final_name;
        if (endsWith(name, open_video)) {
          final_name = withoutSuffix(name, open_video) + extension;
          Found& f = found[camera + "/" + final_name];
          if (f.closed) break;  // a closed file of that name wins
          f.disk_path = relative;
          f.stamp = *stamp;
        } else if (endsWith(name, extension)) {
          Found& f = found[relative];
          f.closed = true;
          f.disk_path = relative;
          f.stamp = *stamp;
          final_name = name;
        } else if (endsWith(name, closed_sidecar)) {
          sidecars[camera + "/" + withoutSuffix(name, kSidecarSuffix)] = {relative, true};
          break;
        } else if (endsWith(name, open_sidecar)) {
          auto& sidecar = sidecars[camera + "/" +
                                   withoutSuffix(name, std::string(kSidecarSuffix) + kIncomplete)];
          if (!sidecar.closed) sidecar = {relative, false};
          break;
        } else {
          continue;
        }
        Found& f = found[camera + "/" + final_name];
        f.camera_id = camera;
        f.file_path = camera + "/" + final_name;
        if (f.file_path.size() > kMaxKeyBytes) {
          report.messages.push_back("skipped '" + f.file_path + "': path over 255 bytes");
          found.erase(f.file_path);
        }
        break;
      }
    }
  }
  for (auto& [file_path, f] : found) {
    auto sidecar = sidecars.find(file_path);
    if (sidecar == sidecars.end()) continue;
    const auto stamp = stampOf(options_.root / sidecar->second.disk_path);
    if (!stamp) continue;
    f.sidecar_disk_path = sidecar->second.disk_path;
    f.sidecar_closed = sidecar->second.closed;
    f.sidecar_stamp = *stamp;
  }
  std::sort(cameras.begin(), cameras.end());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const_cast<Catalogue*>(this)->cameras_ = std::move(cameras);
  }
  return found;
}

Recording Catalogue::refresh(const Found& found, const std::optional<Recording>& known,
                             ScanReport& report) const {
  const bool has_sidecar = !found.sidecar_disk_path.empty();
  const bool closed = found.closedWithSidecar();
  if (known && closed && !known->disk_path.empty() && known->disk_path == found.disk_path &&
      known->stamp == found.stamp && known->sidecar_disk_path == found.sidecar_disk_path &&
      (!has_sidecar || known->sidecar_stamp == found.sidecar_stamp) &&
      !known->catalogued_sha256.empty()) {
    return *known;  // hashed in this very state: nothing to do
  }
  Recording r;
  r.camera_id = found.camera_id;
  r.file_path = found.file_path;
  r.disk_path = found.disk_path;
  r.size_bytes = found.stamp.size;
  if (known) {
    r.catalogued_sha256 = known->catalogued_sha256;
    r.catalogued_sidecar_sha256 = known->catalogued_sidecar_sha256;
    r.catalogued_size = known->catalogued_size;
  }
  if (has_sidecar) {
    r.sidecar_file = found.file_path + kSidecarSuffix;
    r.sidecar_disk_path = found.sidecar_disk_path;
    r.sidecar_size_bytes = found.sidecar_stamp.size;
    try {
      const SidecarSummary summary =
          readSidecarSummary(options_.root / found.sidecar_disk_path, !found.sidecar_closed);
      r.frame_count = summary.frames;
      r.start_time_s = summary.first_camera_time_s;
      r.end_time_s = summary.last_camera_time_s;
    } catch (const std::exception& e) {
      // A sidecar being written may be caught mid-write; only a closed one is wrong.
      if (found.sidecar_closed) {
        r.problem = std::string("sidecar unreadable, no frame times: ") + e.what();
      }
    }
  }
  if (!closed) return r;  // being written (a closed video waits for its sidecar too)
  std::string sha, sidecar_sha;
  std::shared_ptr<const std::vector<Sha256::Digest>> chunk_digests;
  try {
    if (options_.chunk_digest_bytes > 0) {
      transfer::FileDigests digests = transfer::sha256OfFileAndChunks(
          options_.root / found.disk_path, options_.chunk_digest_bytes);
      sha = std::move(digests.sha256);
      chunk_digests =
          std::make_shared<const std::vector<Sha256::Digest>>(std::move(digests.chunks));
    } else {
      sha = transfer::sha256OfFile(options_.root / found.disk_path);
    }
    if (has_sidecar) sidecar_sha = transfer::sha256OfFile(options_.root / found.sidecar_disk_path);
    report.hashed += has_sidecar ? 2 : 1;
  } catch (const std::exception& e) {
    r.problem = e.what();
    report.messages.push_back(r.file_path + ": not catalogued: " + e.what());
    return r;
  }
  // Hashed while something wrote to it: hash again at the next scan, serve nothing meanwhile.
  if (stampOf(options_.root / found.disk_path) != std::optional<FileStamp>(found.stamp) ||
      (has_sidecar && stampOf(options_.root / found.sidecar_disk_path) !=
                          std::optional<FileStamp>(found.sidecar_stamp))) {
    if (r.catalogued_sha256.empty()) return r;  // still being written: nothing to report
    // Closed and catalogued complete before: being modified is a change, not a recording in
    // progress (waiting for a stable state would serve it as "being written" until the next
    // scan, and a pull would skip it without a word).
    r.changed = true;
    r.problem = "file changed after it was catalogued complete: being modified (size " +
                std::to_string(r.catalogued_size) + " -> " + std::to_string(r.size_bytes) +
                " bytes)";
    return r;
  }
  r.stamp = found.stamp;
  r.sidecar_stamp = found.sidecar_stamp;
  if (!r.catalogued_sha256.empty() &&
      (sha != r.catalogued_sha256 || sidecar_sha != r.catalogued_sidecar_sha256)) {
    // Closed recordings never change: this one was truncated or overwritten on the vehicle.
    r.changed = true;
    const bool video_changed = sha != r.catalogued_sha256;
    r.problem =
        std::string(video_changed ? "file" : "sidecar") +
        " changed after it was catalogued complete: " +
        (video_changed ? "size " + std::to_string(r.catalogued_size) + " -> " +
                             std::to_string(r.size_bytes) + " bytes, sha256 " +
                             shortDigest(r.catalogued_sha256) + "... -> " + shortDigest(sha) + "..."
                       : "sha256 " + shortDigest(r.catalogued_sidecar_sha256) + "... -> " +
                             shortDigest(sidecar_sha) + "...");
    return r;
  }
  r.sha256 = sha;
  r.sidecar_sha256 = sidecar_sha;
  r.chunk_digests = std::move(chunk_digests);
  r.complete = true;
  if (r.catalogued_sha256.empty()) {
    r.catalogued_sha256 = sha;
    r.catalogued_sidecar_sha256 = sidecar_sha;
    r.catalogued_size = r.size_bytes;
  }
  return r;
}

ScanReport Catalogue::scan() {
  std::lock_guard<std::mutex> scan_lock(scan_mutex_);
  ScanReport report;
  const std::map<std::string, Found> found = walk(report);
  std::map<std::string, Recording> known;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    known = recordings_;
    size_t pending = 0;
    for (const auto& [path, f] : found) {
      auto it = known.find(path);
      if (f.closed && (it == known.end() || it->second.stamp != f.stamp)) ++pending;
    }
    pending_ = pending;
    walked_ = true;
    last_walk_ = found;
  }
  for (const auto& [path, f] : found) {
    auto it = known.find(path);
    std::optional<Recording> previous;
    if (it != known.end()) previous = it->second;
    const bool counted_pending = f.closed && (!previous || previous->stamp != f.stamp);
    Recording fresh = refresh(f, previous, report);
    std::lock_guard<std::mutex> lock(mutex_);
    if (counted_pending && pending_ > 0) --pending_;
    auto current = recordings_.find(path);
    if (current != recordings_.end() && visibleFields(current->second) == visibleFields(fresh) &&
        current->second.stamp == fresh.stamp) {
      continue;
    }
    if (fresh.changed && (current == recordings_.end() || !current->second.changed ||
                          current->second.problem != fresh.problem)) {
      report.messages.push_back(path + ": " + fresh.problem);
    }
    recordings_[path] = std::move(fresh);
    ++generation_;
    report.modified = true;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = recordings_.begin(); it != recordings_.end();) {
    if (found.count(it->first) == 0) {
      report.messages.push_back(it->first + ": removed from the recordings folder");
      it = recordings_.erase(it);
      ++generation_;
      report.modified = true;
    } else {
      ++it;
    }
  }
  pending_ = 0;
  return report;
}

std::vector<Recording> Catalogue::list(const std::string& camera_id,
                                       bool include_incomplete) const {
  std::vector<Recording> result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [path, r] : recordings_) {
      if (!camera_id.empty() && r.camera_id != camera_id) continue;
      if (!r.complete && !include_incomplete) continue;
      result.push_back(r);
    }
  }
  std::sort(result.begin(), result.end(), [](const Recording& a, const Recording& b) {
    return std::tie(a.camera_id, a.start_time_s, a.file_path) <
           std::tie(b.camera_id, b.start_time_s, b.file_path);
  });
  return result;
}

bool Catalogue::hasCamera(const std::string& camera_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (std::binary_search(cameras_.begin(), cameras_.end(), camera_id)) return true;
  for (const auto& [path, r] : recordings_) {
    if (r.camera_id == camera_id) return true;
  }
  return false;
}

size_t Catalogue::pendingFiles() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pending_;
}

size_t Catalogue::pendingNow() const {
  ScanReport ignored;  // the next scan reports the same problems
  const std::map<std::string, Found> found = walk(ignored);
  std::lock_guard<std::mutex> lock(mutex_);
  size_t changed_since_scan = 0;
  for (const auto& [path, f] : found) {
    // Compared with what the last scan saw, not with what it hashed: a file the scan could not
    // hash stays in the same state and must not look pending for ever.
    auto seen = last_walk_.find(path);
    if (f.closedWithSidecar() && (seen == last_walk_.end() || !seen->second.sameState(f))) {
      ++changed_since_scan;
    }
  }
  return pending_ + changed_since_scan;
}

bool Catalogue::walked() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return walked_;
}

uint64_t Catalogue::generation() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return generation_;
}

std::optional<ServedFile> Catalogue::servedFile(const std::string& file_path) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = recordings_.find(file_path);
  if (it != recordings_.end()) {
    if (!it->second.complete) return std::nullopt;
    return ServedFile{it->second.disk_path, it->second.stamp};
  }
  // A sidecar: "<recording>.frames.csv".
  if (endsWith(file_path, kSidecarSuffix)) {
    it = recordings_.find(withoutSuffix(file_path, kSidecarSuffix));
    if (it != recordings_.end() && it->second.complete && it->second.sidecar_file == file_path) {
      return ServedFile{it->second.sidecar_disk_path, it->second.sidecar_stamp};
    }
  }
  return std::nullopt;
}

std::optional<std::string> Catalogue::chunkDigest(const std::string& file_path,
                                                  const FileStamp& stamp, uint64_t offset,
                                                  uint64_t length) const {
  const uint64_t grid = options_.chunk_digest_bytes;
  if (grid == 0 || offset % grid != 0) return std::nullopt;
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = recordings_.find(file_path);
  if (it == recordings_.end()) return std::nullopt;
  const Recording& r = it->second;
  if (!r.complete || r.stamp != stamp || !r.chunk_digests) return std::nullopt;
  const uint64_t index = offset / grid;
  if (index >= r.chunk_digests->size() || offset >= r.stamp.size) return std::nullopt;
  if (length != std::min(grid, r.stamp.size - offset)) return std::nullopt;
  return Sha256::toHex((*r.chunk_digests)[index]);
}

void Catalogue::reportChanged(const std::string& file_path, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = findRecordingOf(recordings_, file_path);
  if (it == recordings_.end() || !it->second.complete) return;
  Recording& r = it->second;
  r.complete = false;
  r.changed = true;
  r.sha256.clear();
  r.sidecar_sha256.clear();
  r.chunk_digests.reset();
  r.problem = why;
  r.stamp = FileStamp{};  // the next scan hashes it again and decides
  ++generation_;
}

std::optional<std::string> Catalogue::changedProblem(const std::string& file_path) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = findRecordingOf(recordings_, file_path);
  if (it == recordings_.end() || !it->second.changed) return std::nullopt;
  return it->second.problem;
}

}  // namespace auv::recorder
