#pragma once
// Errors of the reconstruction stages and the checks of their options (docs/contributing.md,
// rules 4 and 6).

#include <sstream>
#include <stdexcept>
#include <string>

#include "auv/config/errors.h"

namespace auv::recon {

/// A stage cannot do its work with what it was given (too few registered images, an empty
/// cloud, a truncated video, ...). The message names the stage and the cause; the CLI prints it
/// and exits 1 (a RuntimeFailure). Earlier outputs in the survey stay untouched (StagedOutput).
class StageError : public config::RuntimeFailure {
 public:
  StageError(const std::string& stage, const std::string& cause)
      : config::RuntimeFailure(stage + ": " + cause), stage_(stage) {}
  const std::string& stage() const { return stage_; }

 private:
  std::string stage_;
};

/// A stage did part of its work and wrote it, flagged partial (e.g. SfM registered fewer
/// images than asked for: the model that did register is in sparse-partial/). Exit 1 like any
/// StageError, so that `auv recon run` stops there unless told to accept partial results.
class PartialResult : public StageError {
 public:
  using StageError::StageError;
};

/// An option value outside its range: "<field> = <value>: <requirement>". A
/// std::invalid_argument, like every options check() of the cores: exit code 2
/// (config::exitCodeFor).
class OptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

namespace detail {
template <class T>
[[noreturn]] void throwOptionError(const char* field, const T& value, const char* requirement) {
  std::ostringstream message;
  message << field << " = " << value << ": " << requirement;
  throw OptionError(message.str());
}
}  // namespace detail

}  // namespace auv::recon

/// For `Options::check()`: throws OptionError naming the field and its value when `cond` fails,
/// e.g. `AUV_RECON_CHECK_OPTION(min_features > 0, min_features, "must be > 0");`.
#define AUV_RECON_CHECK_OPTION(cond, field, requirement)                             \
  do {                                                                               \
    if (!(cond)) ::auv::recon::detail::throwOptionError(#field, field, requirement); \
  } while (false)
