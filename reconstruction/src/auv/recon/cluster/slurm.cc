#include "auv/recon/cluster/slurm.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <sstream>

extern char** environ;

namespace auv::recon::cluster {

namespace {

/// Closes both ends of pipes on scope exit.
struct Pipe {
  int fd[2] = {-1, -1};
  ~Pipe() {
    for (int f : fd) {
      if (f >= 0) close(f);
    }
  }
};

/// The text of `output` with its trailing newlines removed.
std::string trimmed(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

/// "key=value" fields of scontrol's one-line output ("-o").
std::string field(const std::string& line, const std::string& key) {
  const std::string marker = key + "=";
  size_t at = 0;
  while ((at = line.find(marker, at)) != std::string::npos) {
    if (at == 0 || line[at - 1] == ' ') {
      const size_t begin = at + marker.size();
      return line.substr(begin, line.find(' ', begin) - begin);
    }
    at += marker.size();
  }
  return "";
}

/// A command's failure, for a ClusterError: what ran and what it said.
std::string failure(const std::vector<std::string>& argv, const CommandOutput& result) {
  std::string command = argv.front();
  for (size_t i = 1; i < argv.size() && i < 4; ++i) command += " " + argv[i];
  const std::string said = trimmed(result.err.empty() ? result.out : result.err);
  return command + " failed (exit " + std::to_string(result.exit_code) + ")" +
         (said.empty() ? "" : ": " + said);
}

}  // namespace

CommandOutput runCommand(const std::vector<std::string>& argv, double timeout_s) {
  if (argv.empty()) throw std::invalid_argument("runCommand: no command");
  Pipe out, err;
  if (pipe2(out.fd, O_CLOEXEC) != 0 || pipe2(err.fd, O_CLOEXEC) != 0) {
    throw std::runtime_error(std::string("runCommand: pipe: ") + std::strerror(errno));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out.fd[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err.fd[1], 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  CommandOutput result;
  if (spawned != 0) {
    result.exit_code = 127;
    result.err = argv.front() + ": " + std::strerror(spawned);
    return result;
  }
  close(out.fd[1]);
  close(err.fd[1]);
  out.fd[1] = err.fd[1] = -1;
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
  pollfd fds[2] = {{out.fd[0], POLLIN, 0}, {err.fd[0], POLLIN, 0}};
  std::string* texts[2] = {&result.out, &result.err};
  while (fds[0].fd >= 0 || fds[1].fd >= 0) {
    int wait_ms = -1;
    if (timeout_s > 0) {
      const double left =
          timeout_s -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0) {
        timed_out = true;
        kill(pid, SIGKILL);
        break;
      }
      wait_ms = static_cast<int>(left * 1000) + 1;
    }
    if (poll(fds, 2, wait_ms) < 0 && errno != EINTR) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      char buffer[4096];
      const ssize_t n = read(fds[i].fd, buffer, sizeof buffer);
      if (n > 0) {
        texts[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        fds[i].fd = -1;
      }
    }
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = timed_out             ? 124
                     : WIFEXITED(status)   ? WEXITSTATUS(status)
                     : WIFSIGNALED(status) ? 128 + WTERMSIG(status)
                                           : -1;
  return result;
}

namespace slurm {

void checkAvailable() {
  const CommandOutput version = runCommand({"sbatch", "--version"}, 30);
  if (version.exit_code == 127) {
    throw ClusterError(
        "--executor slurm: no Slurm on this machine (sbatch not found on PATH); install the "
        "cluster's client commands, or run with --executor local");
  }
}

std::vector<std::string> partitions(std::string* default_partition) {
  const std::vector<std::string> argv = {"sinfo", "--noheader", "--format=%P"};
  const CommandOutput result = runCommand(argv, 60);
  if (result.exit_code != 0) {  // the first question asked of the controller
    throw ClusterError("--executor slurm: Slurm's controller cannot be reached: " +
                       trimmed(result.err) + " (is SLURM_CONF the cluster's?)");
  }
  std::vector<std::string> names;
  if (default_partition != nullptr) default_partition->clear();
  std::istringstream lines(result.out);
  for (std::string name; std::getline(lines, name);) {
    name = trimmed(name);
    if (name.empty()) continue;
    if (name.back() == '*') {
      name.pop_back();
      if (default_partition != nullptr) *default_partition = name;
    }
    names.push_back(name);
  }
  return names;
}

std::string submit(const std::vector<std::string>& args, const std::filesystem::path& script) {
  std::vector<std::string> argv = {"sbatch", "--parsable"};
  argv.insert(argv.end(), args.begin(), args.end());
  argv.push_back(script.string());
  const CommandOutput result = runCommand(argv, 120);
  if (result.exit_code != 0) throw ClusterError(failure(argv, result));
  // --parsable: "<id>" or "<id>;<cluster>".
  std::string id = trimmed(result.out);
  id = id.substr(0, id.find(';'));
  if (id.empty() || id.find_first_not_of("0123456789_") != std::string::npos) {
    throw ClusterError("sbatch gave no job id: '" + trimmed(result.out) + "'");
  }
  return id;
}

JobInfo job(const std::string& id) {
  JobInfo info;
  info.id = id;
  const CommandOutput result = runCommand({"scontrol", "--oneliner", "show", "job", id}, 60);
  if (result.exit_code != 0) return info;  // Slurm forgot it: UNKNOWN
  // One line per task of an array job (pending tasks may share one): the job is as far as its
  // least advanced task, and failed if any task failed.
  auto rank = [](const std::string& state) {
    if (state == "COMPLETED") return 0;
    if (state == "PENDING") return 2;
    if (state == "RUNNING" || state == "COMPLETING" || state == "CONFIGURING") return 1;
    return 3;  // FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY, NODE_FAIL, ...
  };
  std::istringstream lines(result.out);
  bool first = true;
  for (std::string line; std::getline(lines, line);) {
    const std::string state = field(line, "JobState");
    if (state.empty()) continue;
    if (first || rank(state) > rank(info.state)) {
      info.state = state;
      info.reason = field(line, "Reason");
      info.exit_code = field(line, "ExitCode");
    }
    const std::string nodes = field(line, "NodeList");
    if (!nodes.empty() && nodes != "(null)" && info.nodes.find(nodes) == std::string::npos) {
      info.nodes += (info.nodes.empty() ? "" : ",") + nodes;
    }
    info.elapsed = std::max(info.elapsed, field(line, "RunTime"));  // same width: text order
    first = false;
  }
  if (info.reason == "None") info.reason.clear();
  return info;
}

void cancel(const std::vector<std::string>& ids) {
  if (ids.empty()) return;
  std::vector<std::string> argv = {"scancel"};
  argv.insert(argv.end(), ids.begin(), ids.end());
  const CommandOutput result = runCommand(argv, 60);
  if (result.exit_code != 0) throw ClusterError(failure(argv, result));
}

bool finished(const std::string& state) {
  return state != "PENDING" && state != "RUNNING" && state != "CONFIGURING" &&
         state != "COMPLETING" && state != "REQUEUED" && state != "RESIZING" &&
         state != "SUSPENDED" && state != "STOPPED";
}

}  // namespace slurm
}  // namespace auv::recon::cluster
