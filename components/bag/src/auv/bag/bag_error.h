#pragma once
// The errors of auv_bag. A damaged file is not one of them: the reader reports damage as
// values (Damage) and reads what is intact; these are for what cannot be done at all.

#include <string>

#include "auv/config/errors.h"

namespace auv::bag {

/// A bag could not be written or opened; the text names the file. EXISTS, NOT_FOUND and
/// NOT_MCAP are the user's input (exit code 2: choose another name, give an MCAP file), IO a
/// failure (1).
class BagError : public config::Error {
 public:
  enum class Kind { EXISTS, NOT_FOUND, NOT_MCAP, IO };
  BagError(Kind kind, const std::string& text) : Error(text), kind_(kind) {}
  Kind kind() const { return kind_; }
  int exitCode() const override {
    return kind_ == Kind::IO ? config::RuntimeFailure::kExitCode : config::ConfigError::kExitCode;
  }

 private:
  Kind kind_;
};

}  // namespace auv::bag
