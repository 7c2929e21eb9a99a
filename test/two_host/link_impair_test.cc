// auv_link_impair (README.md): the decision core without root (LinkImpairCore), then the tool
// itself on the loopback of a network namespace of the test's own, fed by an iptables NFQUEUE
// rule (LinkImpairNamespace; skipped where namespaces or iptables are not allowed). Nothing
// leaves that namespace.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "link_impair.h"
#include "netns_harness.h"

namespace auv::link_impair {
namespace {

// One packet's fate in a simulated run.
struct Record {
  uint32_t id = 0;
  int64_t arrival_us = 0;
  Decision decision;
};

struct Simulation {
  std::vector<Record> records;   // in arrival order
  std::vector<uint32_t> passed;  // ids in the order they were accepted
  Counters counters;
};

// `count` packets `spacing_us` apart; held packets are taken whenever the clock moves (every
// packet) and the rest at the end, as the tool's loop does. Checks that takeDue never releases a
// packet before its time.
Simulation simulate(const Options& options, int count, int64_t spacing_us) {
  Impairer impairer(options);
  Simulation run;
  std::vector<uint32_t> due;
  auto take = [&](int64_t now) {
    due.clear();
    impairer.takeDue(now, &due);
    for (uint32_t id : due) {
      EXPECT_LE(run.records[id].decision.release_us, now) << "packet " << id << " released early";
      run.passed.push_back(id);
    }
  };
  for (int k = 0; k < count; ++k) {
    const int64_t now = 1000000 + k * spacing_us;
    take(now);
    const Decision decision = impairer.arrive(static_cast<uint32_t>(k), now);
    run.records.push_back({static_cast<uint32_t>(k), now, decision});
    if (decision.verdict == Verdict::kAccept) run.passed.push_back(static_cast<uint32_t>(k));
  }
  const int64_t end = 1000000 + count * spacing_us + 10 * 1000 * 1000;  // all due by then
  take(end);
  EXPECT_EQ(impairer.held(), 0u);
  run.counters = impairer.counters();
  return run;
}

Options withSeed(uint32_t seed) {
  Options options;
  options.seed = seed;
  options.seed_given = true;
  return options;
}

TEST(LinkImpairCore, DropFractionWithinFiveSigmaOfTheLoss) {
  Options options = withSeed(42);
  options.loss = 0.1;
  constexpr int kPackets = 10000;
  const Simulation run = simulate(options, kPackets, 1000);
  int dropped = 0;
  for (const Record& r : run.records) dropped += r.decision.verdict == Verdict::kDrop ? 1 : 0;
  const double fraction = static_cast<double>(dropped) / kPackets;
  const double sigma = std::sqrt(0.1 * 0.9 / kPackets);
  EXPECT_NEAR(fraction, 0.1, 5 * sigma) << dropped << " of " << kPackets << " dropped";
  EXPECT_EQ(run.counters.seen, static_cast<uint64_t>(kPackets));
  EXPECT_EQ(run.counters.dropped, static_cast<uint64_t>(dropped));
  EXPECT_EQ(run.passed.size(), static_cast<size_t>(kPackets - dropped));
  EXPECT_EQ(run.counters.delayed, 0u);  // no delay asked: the rest pass at once
  EXPECT_EQ(run.counters.reordered, 0u);
  EXPECT_TRUE(std::is_sorted(run.passed.begin(), run.passed.end()));
}

TEST(LinkImpairCore, ReleaseTimesWithinDelayPlusMinusJitter) {
  Options options = withSeed(7);
  options.delay_ms = 30;
  options.jitter_ms = 20;
  const Simulation run = simulate(options, 5000, 1000);
  int64_t shortest = INT64_MAX, longest = 0;
  double sum = 0;
  for (const Record& r : run.records) {
    ASSERT_EQ(r.decision.verdict, Verdict::kHold);
    const int64_t hold = r.decision.release_us - r.arrival_us;
    ASSERT_GE(hold, 10000) << "packet " << r.id;
    ASSERT_LE(hold, 50000) << "packet " << r.id;
    shortest = std::min(shortest, hold);
    longest = std::max(longest, hold);
    sum += static_cast<double>(hold);
  }
  // Uniform over [10, 50] ms: 5000 draws come close to both ends and average near 30 ms.
  EXPECT_LT(shortest, 10500);
  EXPECT_GT(longest, 49500);
  const double mean = sum / 5000;
  const double sigma_of_mean = 40000 / std::sqrt(12.0) / std::sqrt(5000.0);
  EXPECT_NEAR(mean, 30000, 5 * sigma_of_mean);
  EXPECT_EQ(run.counters.delayed, 5000u);
  EXPECT_EQ(run.passed.size(), 5000u);
  // Released in the order of their release times.
  for (size_t i = 1; i < run.passed.size(); ++i) {
    EXPECT_LE(run.records[run.passed[i - 1]].decision.release_us,
              run.records[run.passed[i]].decision.release_us);
  }
}

TEST(LinkImpairCore, JitterLargerThanSpacingReorders) {
  Options options = withSeed(3);
  options.delay_ms = 30;
  options.jitter_ms = 20;
  const Simulation run = simulate(options, 1000, 1000);  // 1 ms apart, +-20 ms
  ASSERT_EQ(run.passed.size(), 1000u);
  EXPECT_FALSE(std::is_sorted(run.passed.begin(), run.passed.end()));
  // Overtakers counted by the core are those released ahead of an earlier packet.
  uint64_t overtakers = 0;
  std::set<uint32_t> released;
  for (uint32_t id : run.passed) {
    for (uint32_t earlier = 0; earlier < id; ++earlier) {
      if (released.count(earlier) == 0) {
        ++overtakers;
        break;
      }
    }
    released.insert(id);
  }
  EXPECT_EQ(run.counters.reordered, overtakers);
  EXPECT_GT(overtakers, 100u);

  // Without jitter a fixed delay keeps the order.
  options.jitter_ms = 0;
  const Simulation steady = simulate(options, 1000, 1000);
  EXPECT_TRUE(std::is_sorted(steady.passed.begin(), steady.passed.end()));
  EXPECT_EQ(steady.counters.reordered, 0u);
}

TEST(LinkImpairCore, ReorderHoldsSomePacketsBackSoLaterOnesOvertake) {
  Options options = withSeed(5);
  options.delay_ms = 5;
  options.reorder = 0.25;
  options.reorder_delay_ms = 20;
  const Simulation run = simulate(options, 4000, 1000);
  int held_back = 0;
  for (const Record& r : run.records) {
    const int64_t hold = r.decision.release_us - r.arrival_us;
    ASSERT_TRUE(hold == 5000 || hold == 25000) << "packet " << r.id << " held " << hold << " us";
    held_back += hold == 25000 ? 1 : 0;
  }
  EXPECT_NEAR(held_back / 4000.0, 0.25, 5 * std::sqrt(0.25 * 0.75 / 4000));
  EXPECT_EQ(run.counters.held_back, static_cast<uint64_t>(held_back));
  EXPECT_GT(run.counters.reordered, 0u);
  EXPECT_FALSE(std::is_sorted(run.passed.begin(), run.passed.end()));
}

TEST(LinkImpairCore, SameSeedSameDecisionsOtherSeedOthers) {
  Options options = withSeed(1234);
  options.loss = 0.2;
  options.delay_ms = 30;
  options.jitter_ms = 20;
  options.reorder = 0.1;
  const Simulation a = simulate(options, 3000, 1000);
  const Simulation b = simulate(options, 3000, 1000);
  ASSERT_EQ(a.records.size(), b.records.size());
  for (size_t i = 0; i < a.records.size(); ++i) {
    EXPECT_EQ(a.records[i].decision.verdict, b.records[i].decision.verdict) << i;
    EXPECT_EQ(a.records[i].decision.release_us, b.records[i].decision.release_us) << i;
  }
  EXPECT_EQ(a.passed, b.passed);
  options.seed = 1235;
  const Simulation c = simulate(options, 3000, 1000);
  EXPECT_NE(a.passed, c.passed);

  // The k-th packet's fate depends on the seed and k only, not on arrival times.
  const Simulation d = simulate(withSeed(0), 1, 1);  // (sanity: a run of one packet works)
  EXPECT_EQ(d.passed.size(), 1u);
  options.seed = 1234;
  const Simulation e = simulate(options, 3000, 250);
  for (size_t i = 0; i < a.records.size(); ++i) {
    EXPECT_EQ(a.records[i].decision.verdict, e.records[i].decision.verdict) << i;
    EXPECT_EQ(a.records[i].decision.release_us - a.records[i].arrival_us,
              e.records[i].decision.release_us - e.records[i].arrival_us)
        << i;
  }
}

TEST(LinkImpairCore, BeyondCapacityPacketsPassAtOnce) {
  Options options = withSeed(9);
  options.delay_ms = 100;
  options.capacity = 5;
  Impairer impairer(options);
  int held = 0, passed = 0;
  for (uint32_t id = 0; id < 12; ++id) {
    const Decision d = impairer.arrive(id, 1000);
    held += d.verdict == Verdict::kHold ? 1 : 0;
    passed += d.verdict == Verdict::kAccept ? 1 : 0;
  }
  EXPECT_EQ(held, 5);
  EXPECT_EQ(passed, 7);
  EXPECT_EQ(impairer.counters().overflow, 7u);
  EXPECT_EQ(impairer.counters().reordered, 7u);  // they pass the five held ones
  EXPECT_EQ(impairer.nextRelease().value_or(0), 1000 + 100000);
  std::vector<uint32_t> ids;
  impairer.takeDue(1000 + 99999, &ids);
  EXPECT_TRUE(ids.empty());
  impairer.takeDue(1000 + 100000, &ids);
  EXPECT_EQ(ids, (std::vector<uint32_t>{0, 1, 2, 3, 4}));  // same time: arrival order
  EXPECT_FALSE(impairer.nextRelease().has_value());
  // Room again.
  EXPECT_EQ(impairer.arrive(99, 200000).verdict, Verdict::kHold);
  ids.clear();
  impairer.takeAll(&ids);
  EXPECT_EQ(ids, std::vector<uint32_t>{99});
  EXPECT_EQ(impairer.held(), 0u);
}

TEST(LinkImpairCore, ParsesOptions) {
  Options o;
  ASSERT_EQ(parseOptions({"--queue", "5", "--loss", "0.2", "--delay=30", "--jitter", "20",
                          "--reorder", "0.05", "--reorder-delay", "15", "--seed", "1", "--capacity",
                          "100", "--stats-every", "2.5"},
                         &o),
            "");
  EXPECT_EQ(o.queue, 5);
  EXPECT_DOUBLE_EQ(o.loss, 0.2);
  EXPECT_DOUBLE_EQ(o.delay_ms, 30);
  EXPECT_DOUBLE_EQ(o.jitter_ms, 20);
  EXPECT_DOUBLE_EQ(o.reorder, 0.05);
  EXPECT_DOUBLE_EQ(o.reorder_delay_ms, 15);
  EXPECT_EQ(o.seed, 1u);
  EXPECT_TRUE(o.seed_given);
  EXPECT_EQ(o.capacity, 100u);
  EXPECT_DOUBLE_EQ(o.stats_every_s, 2.5);
  Options help;
  EXPECT_EQ(parseOptions({"--help"}, &help), "");
  EXPECT_TRUE(help.help);
  EXPECT_NE(usage().find("--reorder-delay"), std::string::npos);
}

TEST(LinkImpairCore, BadOptionsGiveAnErrorNamingTheOption) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{}, "--queue: missing"},
      {{"--queue", "65536"}, "--queue: expected a queue number in 0..65535, got '65536'"},
      {{"--queue", "-1"}, "--queue: expected"},
      {{"--queue", "0", "--loss", "1.5"}, "--loss: expected a probability in [0, 1], got '1.5'"},
      {{"--queue", "0", "--loss", "abc"}, "--loss: expected a probability in [0, 1], got 'abc'"},
      {{"--queue", "0", "--loss", "nan"}, "--loss: expected"},
      {{"--queue", "0", "--reorder", "-0.1"}, "--reorder: expected a probability"},
      {{"--queue", "0", "--delay", "-1"}, "--delay: expected milliseconds in [0, 3600000]"},
      {{"--queue", "0", "--jitter", "10ms"}, "--jitter: expected milliseconds"},
      {{"--queue", "0", "--reorder-delay", ""}, "--reorder-delay: expected milliseconds"},
      {{"--queue", "0", "--seed", "4294967296"}, "--seed: expected an integer in 0..4294967295"},
      {{"--queue", "0", "--capacity", "0"}, "--capacity: expected a number of packets"},
      {{"--queue", "0", "--stats-every", "-2"}, "--stats-every: expected seconds"},
      {{"--queue", "0", "--loss"}, "--loss: missing value"},
      {{"--queue", "0", "--lose", "0.1"}, "unknown option '--lose'"},
  };
  for (const auto& [args, expected] : cases) {
    Options o;
    const std::string error = parseOptions(args, &o);
    EXPECT_EQ(error.rfind(expected, 0), 0u) << "got: " << error << "\nexpected: " << expected;
  }
}

// ---- the tool in a namespace of its own ----

constexpr int kPort = 47011;  // inside the test's namespace only
constexpr const char* kQueue = "5";

struct Datagram {
  uint32_t sequence;
  uint32_t pad;
  int64_t sent_ns;  // CLOCK_REALTIME, as SO_TIMESTAMPNS on the receiving side
};

int64_t realtimeNs() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

// A receiving socket on 127.0.0.1:kPort and a sending socket, both made by a thread that entered
// the namespace: sockets stay in the namespace they were made in, whichever thread uses them.
std::string openSockets(const std::string& netns, Fd* receiver, Fd* sender) {
  std::string error;
  std::thread maker([&] {
    Fd ns;
    ns.fd = open(("/run/netns/" + netns).c_str(), O_RDONLY | O_CLOEXEC);
    if (ns.fd < 0 || setns(ns.fd, CLONE_NEWNET) != 0) {
      error = "cannot enter " + netns + ": " + std::strerror(errno);
      return;
    }
    receiver->fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sender->fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(kPort);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const int on = 1;
    const timeval timeout{0, 50 * 1000};
    const int buffer = 4 << 20;
    if (receiver->fd < 0 || sender->fd < 0 ||
        bind(receiver->fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
        setsockopt(receiver->fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on)) != 0 ||
        setsockopt(receiver->fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout)) != 0 ||
        setsockopt(receiver->fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof(buffer)) != 0 ||
        connect(sender->fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
      error = std::string("sockets in the namespace: ") + std::strerror(errno);
    }
  });
  maker.join();
  return error;
}

// Counts what arrives on the receiving socket until stopped (also when the test fails).
class Receiver {
 public:
  struct Arrival {
    uint32_t sequence;
    double delay_ms;  // kernel receive time (SO_TIMESTAMPNS) - send time
  };
  explicit Receiver(int fd) : fd_(fd), thread_([this] { loop(); }) {}
  ~Receiver() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  size_t count() const { return count_; }
  std::vector<Arrival> arrivals() {
    std::lock_guard<std::mutex> lock(mutex_);
    return arrivals_;
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    arrivals_.clear();
    count_ = 0;
  }

 private:
  void loop() {
    while (!stop_) {
      Datagram datagram{};
      iovec io{&datagram, sizeof(datagram)};
      alignas(cmsghdr) char control[256];
      msghdr message{};
      message.msg_iov = &io;
      message.msg_iovlen = 1;
      message.msg_control = control;
      message.msg_controllen = sizeof(control);
      const ssize_t n = recvmsg(fd_, &message, 0);
      if (n != static_cast<ssize_t>(sizeof(datagram))) continue;  // timeout: look at stop_
      int64_t received_ns = realtimeNs();
      for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec stamp{};
          std::memcpy(&stamp, CMSG_DATA(c), sizeof(stamp));
          received_ns = static_cast<int64_t>(stamp.tv_sec) * 1000000000 + stamp.tv_nsec;
        }
      }
      std::lock_guard<std::mutex> lock(mutex_);
      arrivals_.push_back({datagram.sequence, (received_ns - datagram.sent_ns) / 1e6});
      count_ = arrivals_.size();
    }
  }

  int fd_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> count_{0};
  std::mutex mutex_;
  std::vector<Arrival> arrivals_;
  std::thread thread_;
};

// `count` numbered datagrams at ~1 kHz (sequence numbers from `first`).
void sendNumbered(int fd, uint32_t first, int count) {
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < count; ++k) {
    std::this_thread::sleep_until(start + std::chrono::microseconds(1000 * k));
    Datagram datagram{first + static_cast<uint32_t>(k), 0, realtimeNs()};
    ASSERT_EQ(send(fd, &datagram, sizeof(datagram), 0), static_cast<ssize_t>(sizeof(datagram)))
        << std::strerror(errno);
  }
}

// Datagrams received after one with a higher sequence number.
int outOfOrder(const std::vector<Receiver::Arrival>& arrivals) {
  int late = 0;
  uint32_t highest = 0;
  bool any = false;
  for (const Receiver::Arrival& a : arrivals) {
    if (any && a.sequence < highest) ++late;
    highest = any ? std::max(highest, a.sequence) : a.sequence;
    any = true;
  }
  return late;
}

TEST(LinkImpairNamespace, LossDelayAndReorderOnLoopbackThenBypassWhenStopped) {
  const std::string tool = LINK_IMPAIR_EXECUTABLE;
  if (tool.empty()) {
    GTEST_SKIP() << "auv_link_impair was not built: libnetfilter_queue was not found by "
                    "pkg-config at configure time (apt-get install libnetfilter-queue-dev)";
  }
  std::string error;
  const std::unique_ptr<system_tests::OneHost> one = system_tests::OneHost::create("nfq", &error);
  if (!one) GTEST_SKIP() << "network namespaces are not allowed here: " << error;
  const std::string netns = one->host().netns;
  const std::vector<std::string> rule = {"-p",
                                         "udp",
                                         "-o",
                                         "lo",
                                         "-d",
                                         "127.0.0.1",
                                         "--dport",
                                         std::to_string(kPort),
                                         "-j",
                                         "NFQUEUE",
                                         "--queue-num",
                                         kQueue,
                                         "--queue-bypass"};
  std::vector<std::string> add = {"iptables", "-A", "OUTPUT"};
  add.insert(add.end(), rule.begin(), rule.end());
  const system_tests::CommandResult added = one->run(add);
  if (added.exit_code != 0) {
    GTEST_SKIP() << "iptables NFQUEUE rules are not allowed here (exit " << added.exit_code
                 << "): " << added.out;
  }

  Fd receiver_fd, sender_fd;
  error = openSockets(netns, &receiver_fd, &sender_fd);
  ASSERT_EQ(error, "");
  Receiver receiver(receiver_fd.fd);

  const std::string log = testing::TempDir() + "link_impair_" + std::to_string(getpid()) + ".log";
  std::filesystem::remove(log);
  constexpr int kSent = 2000;
  {
    system_tests::BackgroundProcess impairer(one->host(), {},
                                             {tool, "--queue", kQueue, "--loss", "0.2", "--delay",
                                              "30", "--jitter", "20", "--seed", "1"},
                                             log);
    ASSERT_TRUE(system_tests::waitUntil(10.0, [&] {
      return impairer.output().find(" ready: ") != std::string::npos || !impairer.running();
    })) << impairer.output();
    if (!impairer.running() && impairer.waitExit(0) == 3) {
      GTEST_SKIP() << "the NFQUEUE cannot be bound here: " << impairer.output();
    }
    ASSERT_TRUE(impairer.running()) << impairer.output();

    // What the tool must do with seed 1: the k-th packet's fate depends on the seed and k only.
    Options options = withSeed(1);
    options.loss = 0.2;
    options.delay_ms = 30;
    options.jitter_ms = 20;
    Impairer expected(options);
    std::set<uint32_t> expected_passed;
    for (uint32_t k = 0; k < kSent; ++k) {
      if (expected.arrive(k, 0).verdict != Verdict::kDrop) expected_passed.insert(k);
    }

    sendNumbered(sender_fd.fd, 0, kSent);
    // Held at most 50 ms: a bounded wait for the last ones, then a margin for strays.
    system_tests::waitUntil(5.0, [&] { return receiver.count() >= expected_passed.size(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const std::vector<Receiver::Arrival> arrivals = receiver.arrivals();
    EXPECT_EQ(impairer.stop(), 0) << impairer.output();
    const std::string output = impairer.output();

    std::set<uint32_t> received;
    std::vector<double> delays;
    for (const Receiver::Arrival& a : arrivals) {
      EXPECT_TRUE(received.insert(a.sequence).second) << "duplicate " << a.sequence;
      delays.push_back(a.delay_ms);
    }
    ASSERT_FALSE(delays.empty());
    std::sort(delays.begin(), delays.end());
    const double fraction = static_cast<double>(received.size()) / kSent;
    const double median = delays[delays.size() / 2];
    const int late = outOfOrder(arrivals);
    const double sigma = std::sqrt(0.8 * 0.2 / kSent);
    std::cout << "[ figures  ] received " << received.size() << "/" << kSent << " = " << fraction
              << " (expected 0.8 +- " << 5 * sigma << "); one-way delay min " << delays.front()
              << " ms, median " << median << " ms, p95 " << delays[delays.size() * 95 / 100]
              << " ms, max " << delays.back() << " ms; " << late << " datagrams arrived after a "
              << "later-numbered one\n[ tool     ] " << output;
    testing::Test::RecordProperty("received", static_cast<int>(received.size()));
    testing::Test::RecordProperty("median_delay_us", static_cast<int>(median * 1000));
    testing::Test::RecordProperty("out_of_order", late);

    EXPECT_NEAR(fraction, 0.8, 5 * sigma);
    EXPECT_EQ(received, expected_passed) << "the tool's drops differ from the core's with seed 1";
    EXPECT_GE(median, 25.0);
    EXPECT_LE(median, 60.0);
    EXPECT_GE(delays.front(), 10.0 - 1.0) << "a datagram passed without its hold";
    EXPECT_GT(late, 0) << "no reordering with 20 ms jitter at 1 ms spacing";
    // The tool's own counters agree.
    std::smatch counters;
    ASSERT_TRUE(std::regex_search(output, counters,
                                  std::regex("exit \\(SIGINT\\): seen ([0-9]+) dropped ([0-9]+) "
                                             "delayed ([0-9]+) reordered ([0-9]+)")))
        << output;
    EXPECT_EQ(std::stoi(counters[1]), kSent);
    EXPECT_EQ(std::stoi(counters[2]), kSent - static_cast<int>(expected_passed.size()));
    EXPECT_EQ(std::stoi(counters[3]), static_cast<int>(expected_passed.size()));
    EXPECT_GT(std::stoi(counters[4]), 0);
  }

  // Stopping the tool accepts what it still holds: nothing is stranded in the queue.
  receiver.clear();
  {
    const std::string held_log = log + ".held";
    system_tests::BackgroundProcess impairer(
        one->host(), {}, {tool, "--queue", kQueue, "--delay", "60000", "--seed", "2"}, held_log);
    ASSERT_TRUE(system_tests::waitUntil(10.0, [&] {
      return impairer.output().find(" ready: ") != std::string::npos || !impairer.running();
    })) << impairer.output();
    ASSERT_TRUE(impairer.running()) << impairer.output();
    sendNumbered(sender_fd.fd, 50000, 100);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_EQ(receiver.count(), 0u) << "held for 60 s, yet some passed";
    EXPECT_EQ(impairer.stop(), 0) << impairer.output();
    EXPECT_TRUE(system_tests::waitUntil(5.0, [&] { return receiver.count() >= 100; }))
        << receiver.count() << " of 100 held datagrams arrived after the stop\n"
        << impairer.output();
    EXPECT_NE(impairer.output().find("seen 100 dropped 0 delayed 100"), std::string::npos)
        << impairer.output();
    if (!HasFailure()) std::filesystem::remove(held_log);
  }

  // The tool is gone, the rule stays: --queue-bypass lets everything through, in order.
  const system_tests::CommandResult rules = one->run({"iptables", "-S", "OUTPUT"});
  EXPECT_NE(rules.out.find("NFQUEUE"), std::string::npos) << rules.out;
  receiver.clear();
  constexpr int kBypass = 500;
  sendNumbered(sender_fd.fd, 100000, kBypass);
  system_tests::waitUntil(5.0, [&] { return receiver.count() >= kBypass; });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const std::vector<Receiver::Arrival> bypassed = receiver.arrivals();
  EXPECT_EQ(bypassed.size(), static_cast<size_t>(kBypass));
  EXPECT_EQ(outOfOrder(bypassed), 0);
  std::vector<double> bypass_delays;
  for (const Receiver::Arrival& a : bypassed) bypass_delays.push_back(a.delay_ms);
  if (!bypass_delays.empty()) {
    std::sort(bypass_delays.begin(), bypass_delays.end());
    std::cout << "[ figures  ] bypass: received " << bypassed.size() << "/" << kBypass
              << ", median one-way delay " << bypass_delays[bypass_delays.size() / 2] << " ms\n";
  }

  std::vector<std::string> remove = {"iptables", "-D", "OUTPUT"};
  remove.insert(remove.end(), rule.begin(), rule.end());
  EXPECT_EQ(one->run(remove).exit_code, 0);
  receiver.stop();
  if (!HasFailure()) std::filesystem::remove(log);
}

}  // namespace
}  // namespace auv::link_impair
