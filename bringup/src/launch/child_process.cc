#include "child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace auv::bringup {
namespace {

constexpr size_t kReadChunk = 64 * 1024;      // bytes read from a child pipe at a time
constexpr size_t kMaxLineLength = 64 * 1024;  // longer partial lines are flushed as they are

// Writes complete lines as "<prefix><line>\n", one write per line.
void emitLines(OutputStream& stream, const std::string& prefix, bool flush) {
  size_t begin = 0;
  while (true) {
    const size_t newline = stream.partial.find('\n', begin);
    if (newline == std::string::npos) break;
    writeAll(stream.target_fd, prefix + stream.partial.substr(begin, newline - begin + 1));
    begin = newline + 1;
  }
  stream.partial.erase(0, begin);
  if (!stream.partial.empty() && (flush || stream.partial.size() >= kMaxLineLength)) {
    writeAll(stream.target_fd, prefix + stream.partial + "\n");
    stream.partial.clear();
  }
}

// One read() of the pipe into the partial line, complete lines written out; read()'s result
// (errno is read()'s when it is < 0: nothing was written then).
ssize_t readChunk(OutputStream& stream, const std::string& prefix) {
  char buffer[kReadChunk];
  const ssize_t n = read(stream.fd, buffer, sizeof(buffer));
  if (n > 0) {
    stream.partial.append(buffer, static_cast<size_t>(n));
    emitLines(stream, prefix, /*flush=*/false);
  }
  return n;
}

// Writes the last, unterminated line and closes the pipe.
void flushAndClose(OutputStream& stream, const std::string& prefix) {
  emitLines(stream, prefix, /*flush=*/true);
  closeFd(stream.fd);
}

std::vector<char*> nullTerminated(const std::vector<std::string>& strings) {
  std::vector<char*> pointers;
  // posix_spawn takes char* const[] but does not modify the strings.
  for (const std::string& text : strings) pointers.push_back(const_cast<char*>(text.c_str()));
  pointers.push_back(nullptr);
  return pointers;
}

}  // namespace

void writeAll(int fd, const std::string& data) {
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = write(fd, data.data() + done, data.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd pfd{fd, POLLOUT, 0};
      if (poll(&pfd, 1, 1000) <= 0) return;
    } else {
      return;
    }
  }
}

void closeFd(int& fd) {
  if (fd >= 0) close(fd);
  fd = -1;
}

void readAvailable(OutputStream& stream, const std::string& prefix) {
  const ssize_t n = readChunk(stream, prefix);
  if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN && errno != EWOULDBLOCK)) {
    flushAndClose(stream, prefix);
  }
}

void drainAndClose(OutputStream& stream, const std::string& prefix) {
  while (stream.fd >= 0) {
    const ssize_t n = readChunk(stream, prefix);
    if (n <= 0 && !(n < 0 && errno == EINTR)) break;
  }
  flushAndClose(stream, prefix);
}

SpawnedChild spawnInOwnGroup(const std::string& program, const std::vector<std::string>& argv,
                             const std::vector<std::string>& environment) {
  int out_pipe[2];
  int err_pipe[2];
  if (pipe2(out_pipe, O_CLOEXEC) != 0) throw std::runtime_error("Supervisor: pipe failed");
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    close(out_pipe[0]);
    close(out_pipe[1]);
    throw std::runtime_error("Supervisor: pipe failed");
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 34))
  posix_spawn_file_actions_addclosefrom_np(&actions, STDERR_FILENO + 1);
#endif
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes,
                           POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  posix_spawnattr_setpgroup(&attributes, 0);
  sigset_t all_signals;
  sigset_t no_signals;
  sigfillset(&all_signals);
  sigemptyset(&no_signals);
  posix_spawnattr_setsigdefault(&attributes, &all_signals);  // undo inherited SIG_IGN
  posix_spawnattr_setsigmask(&attributes, &no_signals);

  SpawnedChild spawned;
  const std::vector<char*> arg_pointers = nullTerminated(argv);
  const std::vector<char*> env_pointers = nullTerminated(environment);
  spawned.error = posix_spawn(&spawned.pid, program.c_str(), &actions, &attributes,
                              arg_pointers.data(), env_pointers.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  close(out_pipe[1]);
  close(err_pipe[1]);
  if (spawned.error != 0) {
    close(out_pipe[0]);
    close(err_pipe[0]);
    spawned.pid = -1;
    return spawned;
  }
  for (int fd : {out_pipe[0], err_pipe[0]}) fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
  spawned.stdout_fd = out_pipe[0];
  spawned.stderr_fd = err_pipe[0];
  return spawned;
}

}  // namespace auv::bringup
