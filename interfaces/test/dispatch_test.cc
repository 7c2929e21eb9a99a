// Where callbacks run and how the executor is woken: subscriptions with
// CallbackThread::MIDDLEWARE deliver in the vendor's thread without any executor, executor-mode
// subscriptions still run on the executor's thread, and a node's waker wakes its executor on
// every notification (not only the first), and a backlog is taken in bounded batches. Real DDS
// on loopback, both vendors; domains 70..79 and 124..127.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "auv/interfaces/executor.h"
#include "auv/interfaces/node.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct VendorPair {
  Vendor writer;
  Vendor reader;
  int index;  // selects the domain id, so concurrently running tests never share one
};

std::string pairName(const testing::TestParamInfo<VendorPair>& info) {
  return toString(info.param.writer) + "_to_" + toString(info.param.reader);
}

NodeOptions optionsFor(Vendor vendor, int domain) {
  NodeOptions options;
  options.vendor = vendor;
  options.domain_id = domain;
  return options;
}

SubscriptionOptions middleware() {
  SubscriptionOptions options;
  options.callback_thread = CallbackThread::MIDDLEWARE;
  return options;
}

msg::String text(const std::string& data) {
  msg::String m;
  m.data(data);
  return m;
}

// True once the writer and the reader see each other (within 10 s).
template <class T>
bool matchedBothWays(const Publisher<T>& pub, const Subscription<T>& sub) {
  const auto deadline = Clock::now() + 10s;
  while (pub.matchedSubscriptions() == 0 || sub.matchedPublishers() == 0) {
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

// What a middleware callback saw; filled from vendor threads, read by the test thread.
class Received {
 public:
  void add(const std::string& data) {
    std::lock_guard<std::mutex> lock(mutex_);
    data_.push_back(data);
    threads_.insert(std::this_thread::get_id());
    cv_.notify_all();
  }
  size_t count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return data_.size();
  }
  std::vector<std::string> data() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return data_;
  }
  std::set<std::thread::id> threads() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return threads_;
  }
  /// Waits (no executor involved) until `n` samples arrived or `timeout`.
  bool waitFor(size_t n, Clock::duration timeout) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] { return data_.size() >= n; });
  }

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  std::vector<std::string> data_;
  std::set<std::thread::id> threads_;
};

class MiddlewareDispatchTest : public testing::TestWithParam<VendorPair> {};

// No executor exists in this test: whatever arrives was delivered by the vendor's threads.
TEST_P(MiddlewareDispatchTest, DeliversWithoutAnyExecutor) {
  const int domain = 70 + GetParam().index;
  Node writer_node("relay_source", optionsFor(GetParam().writer, domain));
  Node reader_node("relay", optionsFor(GetParam().reader, domain));

  // A latched sample of a writer in the reader's own participant: the vendor may deliver it
  // while the subscription is still being created.
  auto own = reader_node.createPublisher<msg::String>("/dispatch/own", latchedStateQos());
  own->publish(text("latched"));
  Received latched;
  auto own_sub = reader_node.createSubscription<msg::String>(
      "/dispatch/own", latchedStateQos(),
      std::function<void(const msg::String&)>([&](const msg::String& m) { latched.add(m.data()); }),
      middleware());
  EXPECT_EQ(own_sub->callbackThread(), CallbackThread::MIDDLEWARE);
  ASSERT_TRUE(latched.waitFor(1, 10s));
  EXPECT_EQ(latched.data(), std::vector<std::string>{"latched"});

  // Samples of the other node (the other vendor in the cross-vendor pairs).
  Received got;
  auto sub = reader_node.createSubscription<msg::String>(
      "/dispatch/chatter", commandQos(),
      std::function<void(const msg::String&)>([&](const msg::String& m) { got.add(m.data()); }),
      middleware());
  auto pub = writer_node.createPublisher<msg::String>("/dispatch/chatter", commandQos());
  ASSERT_TRUE(matchedBothWays(*pub, *sub));
  // Reliable and matched both ways: each sample arrives; repeat a few so the callback runs
  // more than once.
  for (int i = 0; i < 5; ++i) pub->publish(text("sample " + std::to_string(i)));
  ASSERT_TRUE(got.waitFor(5, 10s)) << "got " << got.count();
  EXPECT_EQ(got.data().front(), "sample 0");
  EXPECT_EQ(got.data().back(), "sample 4");
}

// One node, one topic, one subscription per mode, the node spun by an executor on its own
// thread: executor-mode callbacks run only there, middleware ones never do. Then the
// middleware subscription is destroyed while samples keep coming: no callback after that.
TEST_P(MiddlewareDispatchTest, OnlyExecutorModeRunsOnTheExecutorThread) {
  const int domain = 74 + GetParam().index;
  Node writer_node("source", optionsFor(GetParam().writer, domain));
  Node reader_node("mixed", optionsFor(GetParam().reader, domain));

  std::mutex mutex;  // guards executor_threads and executor_count
  std::set<std::thread::id> executor_threads;
  size_t executor_count = 0;
  auto executor_sub = reader_node.createSubscription<msg::String>(
      "/dispatch/mixed", commandQos(),
      std::function<void(const msg::String&)>([&](const msg::String&) {
        std::lock_guard<std::mutex> lock(mutex);
        executor_threads.insert(std::this_thread::get_id());
        ++executor_count;
      }));
  EXPECT_EQ(executor_sub->callbackThread(), CallbackThread::EXECUTOR);
  Received middleware_got;
  auto middleware_sub = reader_node.createSubscription<msg::String>(
      "/dispatch/mixed", commandQos(),
      std::function<void(const msg::String&)>(
          [&](const msg::String& m) { middleware_got.add(m.data()); }),
      middleware());

  Executor executor;
  executor.add(reader_node);
  std::thread spinner([&] { executor.spin(); });
  const std::thread::id executor_thread = spinner.get_id();
  struct Join {
    Executor& e;
    std::thread& t;
    ~Join() {
      e.shutdown();
      t.join();
    }
  } join{executor, spinner};

  auto pub = writer_node.createPublisher<msg::String>("/dispatch/mixed", commandQos());
  const auto deadline = Clock::now() + 10s;
  while (pub->matchedSubscriptions() < 2 || executor_sub->matchedPublishers() == 0 ||
         middleware_sub->matchedPublishers() == 0) {
    ASSERT_LT(Clock::now(), deadline) << "no match";
    std::this_thread::sleep_for(10ms);
  }
  for (int i = 0; i < 5; ++i) pub->publish(text("sample " + std::to_string(i)));
  ASSERT_TRUE(middleware_got.waitFor(5, 10s)) << "got " << middleware_got.count();
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (executor_count >= 5) break;
    }
    ASSERT_LT(Clock::now(), deadline + 10s) << "executor-mode subscription got " << executor_count;
    std::this_thread::sleep_for(10ms);
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_EQ(executor_threads, std::set<std::thread::id>{executor_thread});
  }
  const std::set<std::thread::id> middleware_threads = middleware_got.threads();
  EXPECT_FALSE(middleware_threads.empty());
  EXPECT_EQ(middleware_threads.count(executor_thread), 0u);

  // Destroyed from this thread while data flows: afterwards nothing more is delivered.
  middleware_sub.reset();
  const size_t after_reset = middleware_got.count();
  for (int i = 5; i < 10; ++i) pub->publish(text("sample " + std::to_string(i)));
  for (;;) {  // the executor-mode subscription proves the later samples were delivered
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (executor_count >= 10) break;
    }
    ASSERT_LT(Clock::now(), deadline + 20s) << "executor-mode subscription got " << executor_count;
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(middleware_got.count(), after_reset);
}

INSTANTIATE_TEST_SUITE_P(AllPairs, MiddlewareDispatchTest,
                         testing::Values(VendorPair{Vendor::CYCLONEDDS, Vendor::CYCLONEDDS, 0},
                                         VendorPair{Vendor::FASTDDS, Vendor::FASTDDS, 1},
                                         VendorPair{Vendor::FASTDDS, Vendor::CYCLONEDDS, 2},
                                         VendorPair{Vendor::CYCLONEDDS, Vendor::FASTDDS, 3}),
                         pairName);

bool pendingNow(Waker& waker) { return waker.waitUntil(Clock::now()); }

TEST(WakerTest, NotificationsCollapseUntilConsumed) {
  Waker waker;
  EXPECT_FALSE(pendingNow(waker));
  waker.notify();
  waker.notify();  // already pending: no second wake-up
  EXPECT_TRUE(pendingNow(waker));
  EXPECT_FALSE(pendingNow(waker));
  waker.notify();  // consumed: the next notification counts again
  EXPECT_TRUE(pendingNow(waker));
}

// A node's waker is never waited on; if it kept (and never cleared) a pending flag of its
// own, only its first notification would reach the executor.
TEST(WakerTest, ForwardingPassesOnEveryNotification) {
  auto executor_waker = std::make_shared<Waker>();
  Waker node_waker;
  node_waker.forwardTo(executor_waker);
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    node_waker.notify();
    EXPECT_TRUE(pendingNow(*executor_waker));
    EXPECT_FALSE(pendingNow(*executor_waker));
  }
  // Several before the executor looks: one wake-up for the lot.
  node_waker.notify();
  node_waker.notify();
  EXPECT_TRUE(pendingNow(*executor_waker));
  EXPECT_FALSE(pendingNow(*executor_waker));
  // Removed from the executor: notifications stay here.
  node_waker.forwardTo(nullptr);
  node_waker.notify();
  EXPECT_FALSE(pendingNow(*executor_waker));
  // Added again: what was pending is handed on.
  node_waker.forwardTo(executor_waker);
  EXPECT_TRUE(pendingNow(*executor_waker));
}

TEST(WakerTest, WaitReturnsWhenNotifiedFromAnotherThread) {
  auto executor_waker = std::make_shared<Waker>();
  Waker node_waker;
  node_waker.forwardTo(executor_waker);
  for (int i = 0; i < 3; ++i) {
    std::thread notifier([&] { node_waker.notify(); });
    // Not a timing check: the deadline only turns a lost wake-up into a failure, not a hang.
    EXPECT_TRUE(executor_waker->waitUntil(Clock::now() + 10s)) << "round " << i;
    notifier.join();
  }
}

// The same through DDS: every sample of an executor-mode subscription reaches the waker its
// node forwards to (what Executor::add sets up), also after the first one was consumed.
class NodeWakerTest : public testing::TestWithParam<Vendor> {};

TEST_P(NodeWakerTest, EverySampleWakesTheForwardTarget) {
  const int domain = 78 + (GetParam() == Vendor::FASTDDS ? 1 : 0);
  Node writer_node("talker", optionsFor(GetParam(), domain));
  Node reader_node("listener", optionsFor(GetParam(), domain));
  std::vector<std::string> got;
  auto sub = reader_node.createSubscription<msg::String>(
      "/dispatch/wake", commandQos(),
      std::function<void(const msg::String&)>(
          [&](const msg::String& m) { got.push_back(m.data()); }));
  auto target = std::make_shared<Waker>();
  reader_node.waker()->forwardTo(target);
  auto pub = writer_node.createPublisher<msg::String>("/dispatch/wake", commandQos());
  ASSERT_TRUE(matchedBothWays(*pub, *sub));
  reader_node.executeReady();  // the subscription starts ready (transient-local history)
  pendingNow(*target);
  for (int i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    pub->publish(text("wake " + std::to_string(i)));
    // The deadline only turns a missing wake-up into a failure instead of a hang.
    ASSERT_TRUE(target->waitUntil(Clock::now() + 10s));
    // The sample may trail its own notification by a moment (Fast DDS): run until it is in.
    const auto until = Clock::now() + 10s;
    while (got.size() < static_cast<size_t>(i + 1) && Clock::now() < until) {
      reader_node.executeReady();
      target->waitUntil(Clock::now() + 10ms);
    }
    ASSERT_EQ(got.size(), static_cast<size_t>(i + 1));
    EXPECT_EQ(got.back(), "wake " + std::to_string(i));
    pendingNow(*target);  // consume any wake-up of this round before the next sample
  }
  reader_node.waker()->forwardTo(nullptr);
}

// A backlog on one topic is taken a bounded batch per executor round: the node's other
// subscriptions (and timers, and other nodes of the executor) run in between, and the backlog
// still arrives whole and in order.
class ExecutorFairnessTest : public testing::TestWithParam<Vendor> {};

TEST_P(ExecutorFairnessTest, ABacklogDoesNotHoldUpOtherSubscriptions) {
  const int domain = 124 + (GetParam() == Vendor::FASTDDS ? 1 : 0);
  constexpr int kBacklog = 200;  // < bulk_transfer's 256: no write blocks while nobody takes
  Node writer_node("flooder", optionsFor(GetParam(), domain));
  Node reader_node("busy", optionsFor(GetParam(), domain));
  std::vector<std::string> flood;
  std::vector<std::string> other;
  auto flood_sub = reader_node.createSubscription<msg::String>(
      "/dispatch/flood", bulkTransferQos(),
      std::function<void(const msg::String&)>(
          [&](const msg::String& m) { flood.push_back(m.data()); }));
  auto other_sub = reader_node.createSubscription<msg::String>(
      "/dispatch/other", commandQos(),
      std::function<void(const msg::String&)>(
          [&](const msg::String& m) { other.push_back(m.data()); }));
  auto flood_pub = writer_node.createPublisher<msg::String>("/dispatch/flood", bulkTransferQos());
  auto other_pub = writer_node.createPublisher<msg::String>("/dispatch/other", commandQos());
  ASSERT_TRUE(matchedBothWays(*flood_pub, *flood_sub));
  ASSERT_TRUE(matchedBothWays(*other_pub, *other_sub));
  for (int i = 0; i < kBacklog; ++i) flood_pub->publish(text(std::to_string(i)));
  other_pub->publish(text("meanwhile"));
  // Acknowledged: every sample is in the reader's history before the executor's first round.
  ASSERT_TRUE(flood_pub->waitForAcknowledgments(10.0));
  ASSERT_TRUE(other_pub->waitForAcknowledgments(10.0));

  reader_node.executeReady();
  EXPECT_EQ(other, std::vector<std::string>{"meanwhile"});
  EXPECT_GT(flood.size(), 0u);
  EXPECT_LT(flood.size(), static_cast<size_t>(kBacklog)) << "one round took the whole backlog";

  const auto until = Clock::now() + 10s;
  while (flood.size() < static_cast<size_t>(kBacklog) && Clock::now() < until) {
    reader_node.executeReady();
  }
  ASSERT_EQ(flood.size(), static_cast<size_t>(kBacklog));
  for (int i = 0; i < kBacklog; ++i) EXPECT_EQ(flood[i], std::to_string(i));
}

// A callback that throws gets its exception to whoever spins, and no sample is lost: neither
// the rest of a batch already taken from the reader (Fast DDS takes a whole batch) nor those
// still in it (with no new sample to wake the subscription, it must stay ready).
TEST_P(ExecutorFairnessTest, ACallbackThatThrowsLosesNoSample) {
  const int domain = 126 + (GetParam() == Vendor::FASTDDS ? 1 : 0);
  constexpr int kSamples = 100;
  Node writer_node("talker", optionsFor(GetParam(), domain));
  Node reader_node("fragile", optionsFor(GetParam(), domain));
  std::vector<std::string> received;
  auto sub = reader_node.createSubscription<msg::String>(
      "/dispatch/fragile", bulkTransferQos(),
      std::function<void(const msg::String&)>([&](const msg::String& m) {
        received.push_back(m.data());
        if (m.data() == "5") throw std::runtime_error("bad sample 5");
      }));
  auto pub = writer_node.createPublisher<msg::String>("/dispatch/fragile", bulkTransferQos());
  ASSERT_TRUE(matchedBothWays(*pub, *sub));
  for (int i = 0; i < kSamples; ++i) pub->publish(text(std::to_string(i)));
  ASSERT_TRUE(pub->waitForAcknowledgments(10.0));

  EXPECT_THROW(reader_node.executeReady(), std::runtime_error);
  const auto until = Clock::now() + 10s;
  while (received.size() < static_cast<size_t>(kSamples) && Clock::now() < until) {
    reader_node.executeReady();
  }
  ASSERT_EQ(received.size(), static_cast<size_t>(kSamples));
  for (int i = 0; i < kSamples; ++i) EXPECT_EQ(received[i], std::to_string(i));
}

INSTANTIATE_TEST_SUITE_P(Vendors, ExecutorFairnessTest,
                         testing::Values(Vendor::CYCLONEDDS, Vendor::FASTDDS),
                         [](const testing::TestParamInfo<Vendor>& info) {
                           return toString(info.param);
                         });

INSTANTIATE_TEST_SUITE_P(Vendors, NodeWakerTest,
                         testing::Values(Vendor::CYCLONEDDS, Vendor::FASTDDS),
                         [](const testing::TestParamInfo<Vendor>& info) {
                           return toString(info.param);
                         });

}  // namespace
}  // namespace auv::interfaces
