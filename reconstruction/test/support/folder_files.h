#pragma once
// Every file under a folder with its bytes: for tests that two runs wrote the same output.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

namespace auv::recon::test_support {

/// Every regular file under `folder`, by path relative to it, with its bytes.
inline std::map<std::string, std::string> filesOf(const std::filesystem::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    files[std::filesystem::relative(entry.path(), folder).string()] =
        std::string(std::istreambuf_iterator<char>(in), {});
  }
  return files;
}

}  // namespace auv::recon::test_support
