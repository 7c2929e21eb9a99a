#pragma once
// Stage outputs that never leave a survey half-written: a stage writes into a staging folder
// beside its final folder and swaps it into place only when everything is written. A stage
// that fails (or is interrupted) leaves the previous output as it was.

#include <filesystem>
#include <string>

namespace auv::recon {

class StagedOutput {
 public:
  /// Stages `final_folder` (e.g. survey.sparse()): creates an empty hidden sibling
  /// `.<name>.staging-<pid>` to write into.
  explicit StagedOutput(std::filesystem::path final_folder);
  ~StagedOutput();  ///< not committed: removes the staging folder, the final one is untouched
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// Where to write.
  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& finalPath() const { return final_; }

  /// Replaces the final folder by the staged one (two renames on one file system; the old
  /// output is removed afterwards).
  void commit();

 private:
  std::filesystem::path final_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

/// Writes `content` to `path` through a temporary name and a rename: readers see the old file
/// or the new one, never a part.
void writeFileAtomically(const std::filesystem::path& path, const std::string& content);

/// `path` + ".tmp-<pid>": the temporary name writeFileAtomically uses, for writers that need
/// their own (e.g. cv::imwrite) before `std::filesystem::rename`.
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

}  // namespace auv::recon
