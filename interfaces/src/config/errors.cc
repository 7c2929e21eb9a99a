#include "auv/config/errors.h"

namespace auv::config {

int exitCodeFor(const std::exception& error) {
  if (const auto* own = dynamic_cast<const Error*>(&error)) return own->exitCode();
  if (dynamic_cast<const std::invalid_argument*>(&error)) return ConfigError::kExitCode;
  return RuntimeFailure::kExitCode;
}

}  // namespace auv::config
