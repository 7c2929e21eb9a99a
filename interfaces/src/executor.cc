#include "auv/interfaces/executor.h"

#include <algorithm>
#include <csignal>

namespace auv::interfaces {
namespace {

// A signal only sets this flag (async-signal-safe); spinning executors poll it at least
// every kMaxWait.
volatile std::sig_atomic_t g_signalled = 0;

void onSignal(int) { g_signalled = 1; }

constexpr auto kMaxWait = std::chrono::milliseconds(100);  // bounds signal-to-exit latency

}  // namespace

Executor::Executor() : waker_(std::make_shared<Waker>()) {}

bool Executor::signalled() { return g_signalled != 0; }

void Executor::add(Node& node) {
  nodes_.push_back(&node);
  node.waker()->forwardTo(waker_);
  waker_->notify();
}

void Executor::remove(Node& node) {
  node.waker()->forwardTo(nullptr);
  nodes_.erase(std::remove(nodes_.begin(), nodes_.end(), &node), nodes_.end());
}

bool Executor::spinSome() {
  bool any = false;
  for (Node* node : nodes_) any = node->executeReady() || any;
  return any;
}

bool Executor::spinOnce(std::chrono::nanoseconds timeout) {
  if (spinSome()) return true;
  auto wait = std::min<std::chrono::nanoseconds>(timeout, kMaxWait);
  for (Node* node : nodes_) {
    if (auto due = node->nanosecondsUntilNextTimer())
      wait = std::min(wait, std::chrono::nanoseconds(*due));
  }
  waker_->waitUntil(std::chrono::steady_clock::now() + wait);
  if (g_signalled) shutdown_ = true;
  return spinSome();
}

void Executor::spin() {
  while (!shutdown_) {
    spinOnce(kMaxWait);
    if (g_signalled) shutdown_ = true;
  }
}

bool Executor::spinUntil(const std::function<bool()>& done, std::chrono::nanoseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done() && !shutdown_) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) break;
    spinOnce(deadline - now);
  }
  return done();
}

void Executor::shutdown() {
  shutdown_ = true;
  waker_->notify();
}

void Executor::installSignalHandlers() {
  struct sigaction action {};
  action.sa_handler = &onSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace auv::interfaces
