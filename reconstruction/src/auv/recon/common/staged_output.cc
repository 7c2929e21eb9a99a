#include "auv/recon/common/staged_output.h"

#include <unistd.h>

#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace auv::recon {

namespace {
/// "a/b/" -> "a/b": a trailing slash leaves an empty file name.
fs::path withoutTrailingSlash(const fs::path& folder) {
  const fs::path clean = folder.lexically_normal();
  return clean.has_filename() ? clean : clean.parent_path();
}

/// A hidden sibling of `folder` on the same file system, so that rename() can swap them.
fs::path sibling(const fs::path& folder, const std::string& tag) {
  return folder.parent_path() /
         ("." + folder.filename().string() + "." + tag + "-" + std::to_string(::getpid()));
}
}  // namespace

StagedOutput::StagedOutput(fs::path final_folder)
    : final_(withoutTrailingSlash(final_folder)), staging_(sibling(final_, "staging")) {
  std::error_code error;
  fs::remove_all(staging_, error);  // left by a crashed run of the same pid
  fs::create_directories(staging_, error);
  if (error) {
    throw std::runtime_error(staging_.string() + ": cannot create: " + error.message());
  }
}

StagedOutput::~StagedOutput() {
  if (committed_) return;
  std::error_code error;
  fs::remove_all(staging_, error);
}

void StagedOutput::commit() {
  if (committed_) return;
  const fs::path old = sibling(final_, "old");
  std::error_code error;
  fs::remove_all(old, error);
  const bool had_final = fs::exists(final_);
  if (had_final) {
    fs::rename(final_, old, error);
    if (error) {
      throw std::runtime_error(final_.string() +
                               ": cannot move the previous output aside: " + error.message());
    }
  }
  fs::rename(staging_, final_, error);
  if (error) {
    if (had_final) fs::rename(old, final_);  // put the previous output back
    throw std::runtime_error(final_.string() +
                             ": cannot put the new output in place: " + error.message());
  }
  committed_ = true;
  fs::remove_all(old, error);
}

fs::path temporaryPathFor(const fs::path& path) {
  return path.string() + ".tmp-" + std::to_string(::getpid());
}

void writeFileAtomically(const fs::path& path, const std::string& content) {
  const fs::path temp = temporaryPathFor(path);
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      fs::remove(temp, ignored);
      throw std::runtime_error(path.string() + ": cannot write");
    }
  }
  std::error_code error;
  fs::rename(temp, path, error);
  if (error) {
    fs::remove(temp, error);
    throw std::runtime_error(path.string() + ": cannot rename into place: " + error.message());
  }
}

}  // namespace auv::recon
