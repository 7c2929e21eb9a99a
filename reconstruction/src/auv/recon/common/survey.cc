#include "auv/recon/common/survey.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <string>

#include "auv/recon/common/stage_error.h"

namespace fs = std::filesystem;

namespace auv::recon {

Survey::Survey(fs::path root) : root_(std::move(root)) {}

Survey::PinholeWorkspace Survey::pinholeWorkspace() const {
  std::error_code error;
  if (fs::exists(undistorted() / "sparse" / "images.txt", error)) {
    return {undistorted() / "sparse", undistorted()};
  }
  return {sparse(), corrected()};
}

std::vector<std::string> Survey::cameraFolders(const fs::path& folder, const std::string& stage) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) {
    throw StageError(stage, folder.string() + ": no such folder");
  }
  std::vector<std::string> cameras;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && !name.empty() && name[0] != '.') cameras.push_back(name);
  }
  if (error) throw StageError(stage, folder.string() + ": cannot list: " + error.message());
  if (cameras.empty()) {
    throw StageError(stage, folder.string() + ": no camera folders (expected <camera>/...)");
  }
  std::sort(cameras.begin(), cameras.end());
  return cameras;
}

void Survey::requireExists(const fs::path& path, const std::string& stage,
                           const std::string& producer) {
  std::error_code error;
  if (!fs::exists(path, error)) {
    throw StageError(stage, path.string() + " not found (run `auv recon " + producer + "` first)");
  }
}

std::vector<fs::path> listFiles(const fs::path& folder,
                                const std::vector<std::string>& extensions) {
  std::vector<fs::path> files;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (!entry.is_regular_file()) continue;
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (std::find(extensions.begin(), extensions.end(), extension) != extensions.end()) {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool recordedSimSpan(const Survey& survey, double& first, double& last) {
  first = std::numeric_limits<double>::infinity();
  last = -first;
  std::error_code error;
  if (!fs::is_directory(survey.recordings(), error)) return false;
  for (const auto& entry : fs::recursive_directory_iterator(survey.recordings(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 11 || name.substr(name.size() - 11) != ".frames.csv") continue;
    std::ifstream in(entry.path());
    std::string line;
    std::getline(in, line);  // header frame,camera_time_s,sim_time_s
    while (std::getline(in, line)) {
      const size_t comma = line.rfind(',');
      if (comma == std::string::npos || comma + 1 >= line.size()) continue;
      try {
        const double t = std::stod(line.substr(comma + 1));
        first = std::min(first, t);
        last = std::max(last, t);
      } catch (const std::exception&) {
        // an empty sim_time_s: a real camera's sidecar
      }
    }
  }
  return first <= last;
}

}  // namespace auv::recon
