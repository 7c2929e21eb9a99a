#include "auv/interfaces/logging.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <stdexcept>

namespace auv::interfaces {

LogLevel logLevelFromString(const std::string& name) {
  if (name == "debug") return LogLevel::DEBUG;
  if (name == "info") return LogLevel::INFO;
  if (name == "warn") return LogLevel::WARN;
  if (name == "error") return LogLevel::ERROR;
  if (name == "fatal") return LogLevel::FATAL;
  throw std::invalid_argument("unknown log level '" + name +
                              "' (expected debug, info, warn, error or fatal)");
}

void Logger::log(LogLevel level, const std::string& message) const {
  if (level < level_) return;
  static const char* kNames[] = {"", "DEBUG", "INFO", "WARN", "ERROR", "FATAL"};
  static std::mutex mutex;  // keeps lines of composed nodes from interleaving
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  const double t = std::chrono::duration<double>(now).count();
  {
    std::lock_guard<std::mutex> lock(mutex);
    std::fprintf(stderr, "[%s] [%.3f] [%s]: %s\n", kNames[static_cast<int>(level)], t,
                 name_.c_str(), message.c_str());
  }
  if (sink_) sink_(level, message);
}

}  // namespace auv::interfaces
