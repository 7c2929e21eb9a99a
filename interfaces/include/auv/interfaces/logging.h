#pragma once
// Logging: one line per event, prefixed with the node name, to stderr and to the `log`
// topic (LogEntry), so `auv topic echo /log` shows every component's lines.

#include <functional>
#include <sstream>
#include <string>

namespace auv::interfaces {

enum class LogLevel { DEBUG = 1, INFO, WARN, ERROR, FATAL };

/// Parses debug|info|warn|error|fatal; throws std::invalid_argument otherwise.
LogLevel logLevelFromString(const std::string& name);

class Logger {
 public:
  using Sink = std::function<void(LogLevel, const std::string& message)>;

  explicit Logger(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }
  void setLevel(LogLevel level) { level_ = level; }
  LogLevel level() const { return level_; }
  /// Extra destination (the node's `log` publisher); called for lines at or above level.
  void setSink(Sink sink) { sink_ = std::move(sink); }

  void log(LogLevel level, const std::string& message) const;
  void debug(const std::string& m) const { log(LogLevel::DEBUG, m); }
  void info(const std::string& m) const { log(LogLevel::INFO, m); }
  void warn(const std::string& m) const { log(LogLevel::WARN, m); }
  void error(const std::string& m) const { log(LogLevel::ERROR, m); }

 private:
  std::string name_;
  LogLevel level_ = LogLevel::INFO;
  Sink sink_;
};

/// Streams a message: AUV_INFO(node.logger(), "reached " << n << " waypoints").
#define AUV_LOG(logger, severity, stream_expr)         \
  do {                                                 \
    if ((severity) >= (logger).level()) {              \
      std::ostringstream auv_log_stream_;              \
      auv_log_stream_ << stream_expr;                  \
      (logger).log((severity), auv_log_stream_.str()); \
    }                                                  \
  } while (0)
#define AUV_DEBUG(logger, s) AUV_LOG(logger, ::auv::interfaces::LogLevel::DEBUG, s)
#define AUV_INFO(logger, s) AUV_LOG(logger, ::auv::interfaces::LogLevel::INFO, s)
#define AUV_WARN(logger, s) AUV_LOG(logger, ::auv::interfaces::LogLevel::WARN, s)
#define AUV_ERROR(logger, s) AUV_LOG(logger, ::auv::interfaces::LogLevel::ERROR, s)

}  // namespace auv::interfaces
