// A reliable keep-all stream (bulk_transfer) to a reader in another process: every write
// succeeds and every sample arrives in order, however often the writer's history fills (Fast
// DDS 2.9 returned TIMEOUT from write() each time its history filled, long before
// max_blocking_time: docs/performance.md, "Keep-all streams"). And a write that really cannot
// go through fails after max_blocking_time naming the topic. Domains 67..69 and 9
// (test/README.md).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/node.h"

extern char** environ;

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;

/// stream_reader (test/helpers) in a child process, its stdout on a pipe.
class StreamReader {
 public:
  StreamReader(Vendor vendor, int domain, int count) {
    int out[2];
    if (::pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    std::vector<std::string> args{AUV_STREAM_READER, toString(vendor), std::to_string(domain),
                                  std::to_string(count)};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int error =
        posix_spawn(&pid_, AUV_STREAM_READER, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(out[1]);
    stdout_ = out[0];
    if (error != 0) throw std::runtime_error(std::string("cannot start ") + AUV_STREAM_READER);
  }
  ~StreamReader() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    ::close(stdout_);
  }
  /// True once the reader printed "ready" (its subscription matched a writer).
  bool waitReady(std::chrono::milliseconds timeout) {
    std::string text;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd fd{stdout_, POLLIN, 0};
      if (::poll(&fd, 1, 100) <= 0) continue;
      char buffer[64];
      const ssize_t got = ::read(stdout_, buffer, sizeof(buffer));
      if (got <= 0) return false;  // exited
      text.append(buffer, static_cast<size_t>(got));
      if (text.find("ready\n") != std::string::npos) return true;
    }
    return false;
  }
  /// The exit status (0: all samples in order), or -1 if it did not end in time.
  int wait(std::chrono::seconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
      }
      std::this_thread::sleep_for(20ms);
    }
    return -1;
  }

 private:
  pid_t pid_ = 0;
  int stdout_ = -1;
};

struct Pair {
  Vendor writer;
  Vendor reader;
  int domain;
};

class KeepAllStreamTest : public testing::TestWithParam<Pair> {};

TEST_P(KeepAllStreamTest, EveryWriteSucceedsAndEverySampleArrivesInOrder) {
  // Twelve times the profile's 256 samples: the writer's history fills again and again.
  constexpr int kCount = 12 * 256;
  const Pair pair = GetParam();
  StreamReader reader(pair.reader, pair.domain, kCount);
  Node node("stream_writer", nodeOptions(pair.writer, pair.domain));
  auto publisher = node.createPublisher<msg::FileChunkReply>("stream", bulkTransferQos());
  ASSERT_TRUE(reader.waitReady(20s)) << "the reader process did not match the writer";
  const auto matched = std::chrono::steady_clock::now() + 20s;
  while (publisher->matchedSubscriptions() == 0 && std::chrono::steady_clock::now() < matched) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(publisher->matchedSubscriptions(), 0);
  msg::FileChunkReply sample;
  sample.data(std::vector<uint8_t>(1024, 0x5a));
  for (int i = 0; i < kCount; ++i) {
    sample.offset(static_cast<uint64_t>(i));
    ASSERT_NO_THROW(publisher->publish(sample)) << "sample " << i;
  }
  EXPECT_EQ(reader.wait(60s), 0) << "the reader did not get every sample in order (its stderr "
                                    "says what arrived)";
}

INSTANTIATE_TEST_SUITE_P(Vendors, KeepAllStreamTest,
                         testing::Values(Pair{Vendor::FASTDDS, Vendor::FASTDDS, 67},
                                         Pair{Vendor::FASTDDS, Vendor::CYCLONEDDS, 68},
                                         Pair{Vendor::CYCLONEDDS, Vendor::FASTDDS, 69}),
                         [](const testing::TestParamInfo<Pair>& info) {
                           return toString(info.param.writer) + "_to_" +
                                  toString(info.param.reader);
                         });

TEST(KeepAllStreamTest, AWriteThatCannotGoThroughFailsNamingTheTopic) {
  // A reader that never takes: its keep-all history fills, it stops acknowledging, and the
  // writer's history fills for good. Fast DDS writer, reader in the same process; domain 9.
  Node writer_node("stuck_writer", nodeOptions(Vendor::FASTDDS, 9));
  Node reader_node("stuck_reader", nodeOptions(Vendor::FASTDDS, 9));
  auto subscription = reader_node.createSubscription<msg::FileChunkReply>(
      "stuck", bulkTransferQos(),
      std::function<void(const msg::FileChunkReply&)>([](const msg::FileChunkReply&) {}));
  auto publisher = writer_node.createPublisher<msg::FileChunkReply>("stuck", bulkTransferQos());
  const auto matched = std::chrono::steady_clock::now() + 20s;
  while (publisher->matchedSubscriptions() == 0 && std::chrono::steady_clock::now() < matched) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(publisher->matchedSubscriptions(), 0);
  msg::FileChunkReply sample;
  std::string error;
  for (int i = 0; i < 4 * 256 && error.empty(); ++i) {
    try {
      publisher->publish(sample);
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
  }
  ASSERT_FALSE(error.empty()) << "a reader that never takes did not stop the writer";
  EXPECT_NE(error.find("'stuck'"), std::string::npos) << error;
  EXPECT_NE(error.find("timeout"), std::string::npos) << error;
}

}  // namespace
}  // namespace auv::interfaces
