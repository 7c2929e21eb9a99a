#pragma once
// Names and field paths shared by the launch file's parser and LaunchDescription::check().

#include <algorithm>
#include <cctype>
#include <string>

namespace auv::bringup::launch_names {

inline bool isIdentifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](unsigned char c) { return std::isalnum(c) || c == '_'; });
}

inline bool isValidComponentName(const std::string& s) {
  return !s.empty() && s[0] != '-' && std::none_of(s.begin(), s.end(), [](unsigned char c) {
    return c == ':' || std::isspace(c) || std::iscntrl(c);
  });
}

inline std::string processPath(size_t index) { return "processes[" + std::to_string(index) + "]"; }

inline std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

}  // namespace auv::bringup::launch_names
