#pragma once
// Temporary recordings roots for the recorder's tests, on the transfer protocol's test files.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "auv/transfer/testing/temp_files.h"

namespace auv::recorder::testing {

using transfer::testing::randomBytes;
using transfer::testing::TempDir;
using transfer::testing::writeFile;

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
