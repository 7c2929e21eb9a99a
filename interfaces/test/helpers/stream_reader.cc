// Test helper (not a test): the receiving process of keep_all_stream_test.cc. Subscribes to
// `stream` (FileChunkReply, bulk_transfer profile) on <vendor> and <domain>, prints "ready" once
// a writer is matched, and takes samples in the middleware thread, checking that `offset`
// counts 0, 1, 2, ... Exits 0 after <count> samples in order; 1 on a gap or after 60 s.
//
//   stream_reader <cyclonedds|fastdds> <domain> <count>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "auv/interfaces/node.h"

int main(int argc, char** argv) {
  using namespace auv::interfaces;
  if (argc != 4) {
    std::fprintf(stderr, "usage: stream_reader <cyclonedds|fastdds> <domain> <count>\n");
    return 2;
  }
  const Vendor vendor = vendorFromString(argv[1]);
  const int domain = std::stoi(argv[2]);
  const uint64_t count = std::stoull(argv[3]);
  Node node("stream_reader", nodeOptions(vendor, domain));
  std::atomic<uint64_t> received{0};
  std::atomic<bool> gap{false};
  SubscriptionOptions in_listener;
  in_listener.callback_thread = CallbackThread::MIDDLEWARE;
  auto subscription = node.createSubscription<auv::msg::FileChunkReply>(
      "stream", bulkTransferQos(),
      std::function<void(const auv::msg::FileChunkReply&)>([&](const auv::msg::FileChunkReply& m) {
        const uint64_t expected = received.load();
        if (m.offset() != expected && !gap.exchange(true)) {
          std::fprintf(stderr, "stream_reader: sample %llu arrived as number %llu\n",
                       static_cast<unsigned long long>(m.offset()),
                       static_cast<unsigned long long>(expected));
        }
        received.store(expected + 1);
      }),
      in_listener);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool ready = false;
  while (std::chrono::steady_clock::now() < deadline && received.load() < count && !gap) {
    if (!ready && subscription->matchedPublishers() > 0) {
      std::printf("ready\n");
      std::fflush(stdout);
      ready = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (gap || received.load() != count) {
    std::fprintf(stderr, "stream_reader: %llu of %llu samples%s\n",
                 static_cast<unsigned long long>(received.load()),
                 static_cast<unsigned long long>(count), gap ? ", out of order" : "");
    return 1;
  }
  return 0;
}
