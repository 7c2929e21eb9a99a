#pragma once
// Temporary recordings roots for the recorder's tests.

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace auv::recorder::testing {

/// A fresh folder under the system temp dir, removed with the object.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    path_ = std::filesystem::temp_directory_path() /
            ("auv_recorder_" + tag + "_" + std::to_string(::getpid()) + "_" +
             std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// `size` incompressible bytes from `seed`.
inline std::string randomBytes(size_t size, uint32_t seed) {
  std::mt19937 generator(seed);
  std::string bytes(size, '\0');
  for (auto& b : bytes) b = static_cast<char>(generator() & 0xFF);
  return bytes;
}

inline void writeFile(const std::filesystem::path& path, const std::string& content) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
}

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A sidecar with `frames` rows at 10 fps from camera time `t0`.
inline std::string sidecarText(int frames, double t0 = 100.0) {
  std::string text = "frame,camera_time_s,sim_time_s\n";
  for (int i = 0; i < frames; ++i) {
    text += std::to_string(i) + "," + std::to_string(t0 + 0.1 * i) + "," + std::to_string(0.1 * i) +
            "\n";
  }
  return text;
}

/// A closed recording `<root>/<camera>/<camera>_NNNN.mp4` with its sidecar; returns the
/// relative path.
inline std::string writeRecording(const std::filesystem::path& root, const std::string& camera,
                                  int number, size_t size, int frames, uint32_t seed) {
  char name[64];
  std::snprintf(name, sizeof(name), "%s_%04d.mp4", camera.c_str(), number);
  const std::string relative = camera + "/" + name;
  writeFile(root / relative, randomBytes(size, seed));
  writeFile(root / (relative + ".frames.csv"), sidecarText(frames, 10.0 * number));
  return relative;
}

}  // namespace auv::recorder::testing
