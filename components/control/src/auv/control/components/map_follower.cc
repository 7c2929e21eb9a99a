#include "auv/control/components/map_follower.h"

#include <utility>

namespace auv::control {

MapFollower::MapFollower(std::string map_id, double resolution, Report report,
                         std::size_t max_queued)
    : max_queued_(max_queued == 0 ? 1 : max_queued),
      report_(std::move(report)),
      replica_(std::move(map_id), resolution),
      thread_([this] { run(); }) {}

MapFollower::~MapFollower() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_changed_.notify_all();
  thread_.join();
}

void MapFollower::push(msg::OctomapUpdate update) {
  std::size_t dropped = 0;
  uint64_t newest_dropped = 0;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.push_back(std::move(update));
    while (queue_.size() > max_queued_) {
      newest_dropped = queue_.front().sequence_number();
      queue_.pop_front();
      ++dropped;
    }
  }
  queue_changed_.notify_all();
  if (dropped > 0 && report_) {
    report_(newest_dropped, std::to_string(dropped) + " update(s) dropped: more than " +
                                std::to_string(max_queued_) +
                                " waiting to be applied; the copy waits for the next FULL map");
  }
}

bool MapFollower::tryRead(const std::function<void(const octomap::OcTree&)>& read) const {
  std::unique_lock<std::mutex> lock(replica_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  read(replica_.tree());
  return true;
}

void MapFollower::waitIdle() {
  std::unique_lock<std::mutex> lock(queue_mutex_);
  queue_changed_.wait(lock, [this] { return stop_ || (queue_.empty() && !applying_); });
}

uint64_t MapFollower::sequence() const {
  std::lock_guard<std::mutex> lock(replica_mutex_);
  return replica_.sequence();
}

void MapFollower::run() {
  for (;;) {
    msg::OctomapUpdate update;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_changed_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      update = std::move(queue_.front());
      queue_.pop_front();
      applying_ = true;
    }
    mapping::MapReplica::Outcome outcome;
    std::string error;
    {
      std::lock_guard<std::mutex> lock(replica_mutex_);
      outcome = replica_.apply(update);
      if (outcome == mapping::MapReplica::Outcome::REJECTED) error = replica_.error();
    }
    if (!error.empty() && report_) report_(update.sequence_number(), error);
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      applying_ = false;
    }
    queue_changed_.notify_all();
  }
}

}  // namespace auv::control
