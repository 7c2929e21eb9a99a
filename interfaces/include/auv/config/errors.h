#pragma once
// The errors auv-inspect reports to a user, and the one exit-code rule of every `auv` command
// (docs/architecture.md, "Errors and exit codes"):
//
//   ConfigError     what the user gave is wrong — a file, a field, a parameter, a launch
//                   argument, a command-line option — fix the input and run again: exit 2
//   RuntimeFailure  the input was fine but the work failed — I/O, a peer that vanished, a stage
//                   that could not complete: exit 1
//
// Each package keeps its own error types (ParameterError, LaunchFileError, MissionError,
// OptionError, StageError, ...) for callers that catch them, derived from one of these two, so
// a command's top level needs one catch and one rule (exitCodeFor). No DDS here: core libraries
// use it too.

#include <exception>
#include <stdexcept>
#include <string>

namespace auv::config {

/// Base of the errors above; the message names what is wrong (file, field, value).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  /// The exit code of a command that ends with this error.
  virtual int exitCode() const = 0;
};

/// The user's input is wrong (exit code 2).
class ConfigError : public Error {
 public:
  using Error::Error;
  int exitCode() const override { return kExitCode; }
  static constexpr int kExitCode = 2;
};

/// The work failed with valid input (exit code 1).
class RuntimeFailure : public Error {
 public:
  using Error::Error;
  int exitCode() const override { return kExitCode; }
  static constexpr int kExitCode = 1;
};

/// The exit code for an exception that ends a command: an Error's own; 2 for
/// std::invalid_argument (the standard library's "bad argument", e.g. from std::stod on an
/// option's text); 1 for anything else.
int exitCodeFor(const std::exception& error);

}  // namespace auv::config
