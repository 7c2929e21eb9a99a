// Two "hosts" for tests and benchmarks: two Linux network namespaces joined by a veth pair,
// created by the test itself and removed at the end even on failure. Programs run inside a
// namespace with `ip netns exec`. Needs root or CAP_NET_ADMIN + CAP_SYS_ADMIN (`ip netns add`
// mounts under /run/netns); `TwoHosts::create` reports why it could not, so tests can skip.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace auv::system_tests {

/// Output and exit status of a finished command.
struct CommandResult {
  int exit_code = -1;  // 128 + N when killed by signal N
  std::string out;     // stdout and stderr together
};

/// Runs argv (no shell), waits, captures its output.
CommandResult runCommand(const std::vector<std::string>& argv);

/// The two namespaces and the veth pair; the destructor kills what still runs inside them and
/// deletes them.
class TwoHosts {
 public:
  struct Host {
    std::string netns;    // e.g. auvtest-2h-1234-veh
    std::string veth;     // its end of the pair, e.g. auv1234v
    std::string address;  // e.g. 10.231.210.1
  };

  /// Creates `auvtest-<tag>-<pid>-{veh,shore}` with 10.231.<pid % 256>.{1,2}/30 on the veth
  /// pair and `lo` up in each. First removes namespaces `auvtest-<tag>-<pid>-*` left by
  /// processes that no longer exist (a run killed by a timeout). Returns nullptr and sets
  /// `error` when the machine does not allow it.
  static std::unique_ptr<TwoHosts> create(const std::string& tag, std::string* error);
  ~TwoHosts();
  TwoHosts(const TwoHosts&) = delete;
  TwoHosts& operator=(const TwoHosts&) = delete;

  const Host& vehicle() const { return vehicle_; }
  const Host& shore() const { return shore_; }

  /// `ip netns exec <host> env <environment> argv...`, waited for.
  CommandResult run(const Host& host, const std::map<std::string, std::string>& environment,
                    const std::vector<std::string>& argv) const;

  /// The link goes down (or up) at the shore's end: the vehicle keeps its address and its own
  /// processes keep talking to each other, as when a tether is unplugged on deck.
  bool setLinkUp(bool up) const;

  /// Limits what the vehicle sends to `rate` (tc tbf, e.g. "128kbit"), so a transfer of small
  /// files lasts long enough to be interrupted.
  bool limitVehicleRate(const std::string& rate) const;

 private:
  TwoHosts() = default;
  void destroy();

  Host vehicle_;
  Host shore_;
  bool created_ = false;
};

/// One namespace `auvtest-<tag>-<pid>` with only `lo` (up), for tests that need a network stack
/// of their own (iptables rules, queues) on loopback. The destructor kills what still runs inside
/// and deletes it.
class OneHost {
 public:
  /// Creates the namespace; first removes namespaces `auvtest-<tag>-<pid>` left by processes that
  /// no longer exist. Returns nullptr and sets `error` when the machine does not allow it.
  static std::unique_ptr<OneHost> create(const std::string& tag, std::string* error);
  ~OneHost();
  OneHost(const OneHost&) = delete;
  OneHost& operator=(const OneHost&) = delete;

  /// netns as named above, veth "lo", address 127.0.0.1.
  const TwoHosts::Host& host() const { return host_; }

  /// `ip netns exec <netns> argv...`, waited for.
  CommandResult run(const std::vector<std::string>& argv) const;

 private:
  OneHost() = default;
  TwoHosts::Host host_;
  bool created_ = false;
};

/// A program running in the background inside a namespace, its output appended to `log_path`.
/// Stopped with SIGINT (then SIGKILL to its process group) when destroyed.
class BackgroundProcess {
 public:
  BackgroundProcess(const TwoHosts::Host& host, const std::map<std::string, std::string>& env,
                    const std::vector<std::string>& argv, const std::string& log_path);
  ~BackgroundProcess();
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  /// True while it runs; collects the exit status once it ended.
  bool running();
  /// Waits up to `seconds` for the end; the exit code (128 + N for signal N), -1 if still running.
  int waitExit(double seconds);
  /// SIGINT, up to `grace_seconds` for the end, then SIGKILL to the group. The exit code.
  int stop(double grace_seconds = 10.0);
  /// What it wrote so far.
  std::string output() const;

 private:
  pid_t pid_ = -1;
  int exit_code_ = -1;
  std::string log_path_;
};

/// Polls `condition` every 100 ms for up to `seconds`; true as soon as it holds. A bounded wait
/// for something that must happen, never a speed assertion.
template <typename Condition>
bool waitUntil(double seconds, Condition condition) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return true;
}

/// Total bytes of the regular files below `folder` (0 if it does not exist).
unsigned long long folderBytes(const std::string& folder);

/// SHA-256 of a file (the recorder's), 64 lowercase hex digits; empty if it cannot be read.
std::string fileSha256(const std::string& path);

/// Relative paths of the regular files below `folder`, sorted.
std::vector<std::string> listFiles(const std::string& folder);

/// `text` with every `from` replaced by `to`.
std::string replaceAll(std::string text, const std::string& from, const std::string& to);

}  // namespace auv::system_tests
