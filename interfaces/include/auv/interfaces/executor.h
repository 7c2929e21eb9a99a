#pragma once
// Spins nodes: waits for work (data, due timers) and runs callbacks on the calling thread.
// Several nodes in one executor share one thread, like an rclcpp SingleThreadedExecutor.

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <vector>

#include "auv/interfaces/node.h"

namespace auv::interfaces {

class Executor {
 public:
  Executor();
  /// Adds a node; the node must outlive its membership (remove it or destroy the executor).
  void add(Node& node);
  void remove(Node& node);
  /// Runs all ready work once without waiting; returns true if anything ran.
  bool spinSome();
  /// Waits up to `timeout` for work, then runs it; returns true if anything ran.
  bool spinOnce(std::chrono::nanoseconds timeout);
  /// Spins until shutdown() (from any thread, or SIGINT/SIGTERM after installSignalHandlers).
  void spin();
  /// Spins until `done()` or `timeout`; returns done().
  bool spinUntil(const std::function<bool()>& done, std::chrono::nanoseconds timeout);
  /// Makes spin() return; safe from any thread.
  void shutdown();
  bool isShutdown() const { return shutdown_; }

  /// SIGINT/SIGTERM make every spinning executor return (Ctrl-C stops `auv run` cleanly).
  static void installSignalHandlers();
  /// True once SIGINT/SIGTERM arrived (for loops outside an executor, e.g. CLI tools).
  static bool signalled();

 private:
  std::shared_ptr<Waker> waker_;
  std::vector<Node*> nodes_;
  std::atomic<bool> shutdown_{false};
};

}  // namespace auv::interfaces
