#include "netns_harness.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "auv/transfer/sha256.h"

namespace auv::system_tests {
namespace fs = std::filesystem;

namespace {

int statusToCode(int status) {
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<char*> cArgv(std::vector<std::string>& argv) {
  std::vector<char*> c;
  for (std::string& a : argv) c.push_back(a.data());
  c.push_back(nullptr);
  return c;
}

std::vector<std::string> inNetns(const std::string& netns,
                                 const std::map<std::string, std::string>& environment,
                                 const std::vector<std::string>& argv) {
  std::vector<std::string> full = {"ip", "netns", "exec", netns, "env"};
  for (const auto& [name, value] : environment) full.push_back(name + "=" + value);
  full.insert(full.end(), argv.begin(), argv.end());
  return full;
}

bool ok(const std::vector<std::string>& argv, std::string* error = nullptr) {
  const CommandResult r = runCommand(argv);
  if (r.exit_code != 0 && error != nullptr) {
    std::string line;
    for (const std::string& a : argv) line += a + " ";
    *error = line + "-> exit " + std::to_string(r.exit_code) + ": " + r.out;
  }
  return r.exit_code == 0;
}

// Kills whatever runs inside `netns` (only this namespace's processes), then deletes it.
void deleteNetns(const std::string& netns) {
  for (int round = 0; round < 20; ++round) {
    const CommandResult pids = runCommand({"ip", "netns", "pids", netns});
    std::istringstream in(pids.out);
    bool any = false;
    for (pid_t pid; in >> pid;) any = kill(pid, SIGKILL) == 0 || any;
    if (!any) break;
    usleep(100 * 1000);
  }
  runCommand({"ip", "netns", "del", netns});
}

// Namespaces `<prefix><pid>...` of earlier runs killed before their cleanup (the pid is gone).
void removeStaleNetns(const std::string& prefix) {
  const CommandResult list = runCommand({"ip", "netns", "list"});
  std::istringstream lines(list.out);
  for (std::string line; std::getline(lines, line);) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.rfind(prefix, 0) != 0) continue;
    const pid_t owner = std::atoi(name.substr(prefix.size()).c_str());
    if (owner > 0 && kill(owner, 0) != 0 && errno == ESRCH) deleteNetns(name);
  }
}

}  // namespace

CommandResult runCommand(const std::vector<std::string>& argv) {
  CommandResult result;
  int fds[2];
  if (pipe(fds) != 0) return result;
  std::vector<std::string> args = argv;
  std::vector<char*> c = cArgv(args);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    const int null_in = open("/dev/null", O_RDONLY);
    dup2(null_in, STDIN_FILENO);
    execvp(c[0], c.data());
    _exit(127);
  }
  close(fds[1]);
  std::array<char, 4096> buffer;
  ssize_t n;
  while ((n = read(fds[0], buffer.data(), buffer.size())) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) result.out.append(buffer.data(), n);
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = statusToCode(status);
  return result;
}

std::unique_ptr<TwoHosts> TwoHosts::create(const std::string& tag, std::string* error) {
  const std::string prefix = "auvtest-" + tag + "-";
  removeStaleNetns(prefix);  // of earlier runs killed before their cleanup

  std::unique_ptr<TwoHosts> hosts(new TwoHosts());
  const std::string pid = std::to_string(getpid());
  const std::string subnet = "10.231." + std::to_string(getpid() % 256) + ".";
  hosts->vehicle_ = {prefix + pid + "-veh", "auv" + pid + "v", subnet + "1"};
  hosts->shore_ = {prefix + pid + "-shore", "auv" + pid + "s", subnet + "2"};
  const Host& v = hosts->vehicle_;
  const Host& s = hosts->shore_;
  if (!ok({"ip", "netns", "add", v.netns}, error)) return nullptr;
  hosts->created_ = true;  // from here on the destructor cleans up
  const bool built =
      ok({"ip", "netns", "add", s.netns}, error) &&
      ok({"ip", "link", "add", v.veth, "type", "veth", "peer", "name", s.veth}, error) &&
      ok({"ip", "link", "set", v.veth, "netns", v.netns}, error) &&
      ok({"ip", "link", "set", s.veth, "netns", s.netns}, error) &&
      ok({"ip", "-n", v.netns, "addr", "add", v.address + "/30", "dev", v.veth}, error) &&
      ok({"ip", "-n", s.netns, "addr", "add", s.address + "/30", "dev", s.veth}, error) &&
      ok({"ip", "-n", v.netns, "link", "set", "lo", "up"}, error) &&
      ok({"ip", "-n", s.netns, "link", "set", "lo", "up"}, error) &&
      ok({"ip", "-n", v.netns, "link", "set", v.veth, "up"}, error) &&
      ok({"ip", "-n", s.netns, "link", "set", s.veth, "up"}, error);
  if (!built) return nullptr;  // the destructor removes what was made
  return hosts;
}

TwoHosts::~TwoHosts() { destroy(); }

void TwoHosts::destroy() {
  if (!created_) return;
  deleteNetns(vehicle_.netns);
  deleteNetns(shore_.netns);  // the veth pair goes with its namespaces
  created_ = false;
}

CommandResult TwoHosts::run(const Host& host, const std::map<std::string, std::string>& env,
                            const std::vector<std::string>& argv) const {
  return runCommand(inNetns(host.netns, env, argv));
}

bool TwoHosts::setLinkUp(bool up) const {
  return ok({"ip", "-n", shore_.netns, "link", "set", shore_.veth, up ? "up" : "down"});
}

bool TwoHosts::limitVehicleRate(const std::string& rate) const {
  // A queue of 64 KiB: Cyclone's datagrams (<= 14.7 kB by default) fit, and at low rates the
  // queue delays heartbeats by a few seconds at most, well inside the 10 s participant lease.
  return ok({"ip", "netns", "exec", vehicle_.netns, "tc", "qdisc", "replace", "dev", vehicle_.veth,
             "root", "tbf", "rate", rate, "burst", "16kb", "limit", "64kb"});
}

std::unique_ptr<OneHost> OneHost::create(const std::string& tag, std::string* error) {
  const std::string prefix = "auvtest-" + tag + "-";
  removeStaleNetns(prefix);
  std::unique_ptr<OneHost> one(new OneHost());
  one->host_ = {prefix + std::to_string(getpid()), "lo", "127.0.0.1"};
  if (!ok({"ip", "netns", "add", one->host_.netns}, error)) return nullptr;
  one->created_ = true;  // from here on the destructor cleans up
  if (!ok({"ip", "-n", one->host_.netns, "link", "set", "lo", "up"}, error)) return nullptr;
  return one;
}

OneHost::~OneHost() {
  if (created_) deleteNetns(host_.netns);
}

CommandResult OneHost::run(const std::vector<std::string>& argv) const {
  return runCommand(inNetns(host_.netns, {}, argv));
}

BackgroundProcess::BackgroundProcess(const TwoHosts::Host& host,
                                     const std::map<std::string, std::string>& env,
                                     const std::vector<std::string>& argv,
                                     const std::string& log_path)
    : log_path_(log_path) {
  std::vector<std::string> args = inNetns(host.netns, env, argv);
  std::vector<char*> c = cArgv(args);
  pid_ = fork();
  if (pid_ == 0) {
    setpgid(0, 0);
    const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    const int null_in = open("/dev/null", O_RDONLY);
    dup2(null_in, STDIN_FILENO);
    dup2(log, STDOUT_FILENO);
    dup2(log, STDERR_FILENO);
    execvp(c[0], c.data());
    _exit(127);
  }
}

BackgroundProcess::~BackgroundProcess() { stop(); }

bool BackgroundProcess::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (waitpid(pid_, &status, WNOHANG) == pid_) {
    exit_code_ = statusToCode(status);
    pid_ = -1;
    return false;
  }
  return true;
}

int BackgroundProcess::waitExit(double seconds) {
  waitUntil(seconds, [this] { return !running(); });
  return running() ? -1 : exit_code_;
}

int BackgroundProcess::stop(double grace_seconds) {
  if (!running()) return exit_code_;
  kill(pid_, SIGINT);
  if (waitExit(grace_seconds) >= 0) return exit_code_;
  kill(-pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
  exit_code_ = statusToCode(status);
  pid_ = -1;
  return exit_code_;
}

std::string BackgroundProcess::output() const {
  std::ifstream in(log_path_);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

unsigned long long folderBytes(const std::string& folder) {
  unsigned long long total = 0;
  std::error_code ec;
  // Files are renamed while we walk: skip what vanished instead of failing.
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code size_ec;
    if (it->is_regular_file(size_ec)) {
      const auto size = it->file_size(size_ec);
      if (!size_ec) total += size;
    }
  }
  return total;
}

std::string fileSha256(const std::string& path) {
  try {
    return transfer::sha256OfFile(path);
  } catch (const std::exception&) {
    return "";  // unreadable: compares unequal to any digest
  }
}

std::vector<std::string> listFiles(const std::string& folder) {
  std::vector<std::string> files;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_ec;
    if (it->is_regular_file(type_ec)) {
      files.push_back(fs::relative(it->path(), folder).generic_string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string replaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

}  // namespace auv::system_tests
