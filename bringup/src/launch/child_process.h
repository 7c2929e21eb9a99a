#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace auv::bringup {

/// One pipe from a child (its stdout or stderr), where its lines go, and the not yet complete
/// last line.
struct OutputStream {
  int fd = -1;         // read end, non-blocking; -1 once closed
  int target_fd = -1;  // receives "<prefix><line>\n", one write per line
  std::string partial;
};

/// Writes everything, retrying on EINTR and waiting out EAGAIN; drops data on other errors
/// (e.g. EPIPE when the reader of our output went away: supervision must go on).
void writeAll(int fd, const std::string& data);

/// Closes `fd` if open and sets it to -1.
void closeFd(int& fd);

/// One read() of the pipe; copies the complete lines to the target. At end of file or on an
/// error, flushes the partial line and closes the pipe.
void readAvailable(OutputStream& stream, const std::string& prefix);

/// Reads whatever the pipe holds without waiting, then flushes the partial line and closes it.
void drainAndClose(OutputStream& stream, const std::string& prefix);

/// A child started by spawnInOwnGroup().
struct SpawnedChild {
  int error = 0;  // posix_spawn's error number; 0 when the child runs
  pid_t pid = -1;
  int stdout_fd = -1;  // read ends, non-blocking, close-on-exec
  int stderr_fd = -1;
};

/// Starts `program` with `argv` and `environment` ("NAME=value") in a process group of its
/// own, stdin from /dev/null, stdout and stderr piped to us, every signal at its default
/// disposition and none blocked (a launcher's SIG_IGN must not leak into components).
/// Throws std::runtime_error when the pipes cannot be made.
SpawnedChild spawnInOwnGroup(const std::string& program, const std::vector<std::string>& argv,
                             const std::vector<std::string>& environment);

}  // namespace auv::bringup
