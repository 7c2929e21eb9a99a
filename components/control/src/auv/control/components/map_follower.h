#pragma once
// The controller's copy of the map (mapping::MapReplica), kept off the control loop. Updates
// from `map/update` are queued and applied by a thread of its own: reading a FULL map takes
// tens of milliseconds for a small site and seconds for a large one, and on the control
// thread that was time without control steps or status (a mission handler that hears no
// status for controller_timeout starts a recovery). Readers never wait for an update either:
// tryRead() declines while one is being applied.

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "auv/mapping/map_replica.h"

namespace auv::control {

class MapFollower {
 public:
  /// Called for an update that changed nothing, `error` saying why: on the follower's thread
  /// for a REJECTED update (MapReplica::error()), on the pushing thread for updates dropped
  /// by an overflowing queue (`sequence_number`: the newest dropped).
  using Report = std::function<void(uint64_t sequence_number, const std::string& error)>;

  /// Follows map `map_id` with leaves of `resolution` m; starts the thread.
  MapFollower(std::string map_id, double resolution, Report report,
              std::size_t max_queued = kDefaultMaxQueued);
  /// Stops the thread; updates still queued are dropped.
  ~MapFollower();
  MapFollower(const MapFollower&) = delete;
  MapFollower& operator=(const MapFollower&) = delete;

  /// Queues an update (any thread). When more than max_queued wait, the oldest are dropped:
  /// the copy then misses increments and waits for the next FULL map (MapReplica's GAP).
  void push(msg::OctomapUpdate update);
  /// Calls `read` with the copy unless an update is being applied; false when it did not.
  bool tryRead(const std::function<void(const octomap::OcTree&)>& read) const;
  /// Blocks until every update pushed before is applied.
  void waitIdle();
  /// The version of the map held (0: none yet).
  uint64_t sequence() const;

  static constexpr std::size_t kDefaultMaxQueued = 64;

 private:
  void run();

  const std::size_t max_queued_;
  Report report_;
  mutable std::mutex replica_mutex_;
  mapping::MapReplica replica_;  // guarded by replica_mutex_
  std::mutex queue_mutex_;
  std::condition_variable queue_changed_;
  std::deque<msg::OctomapUpdate> queue_;  // guarded by queue_mutex_
  bool applying_ = false;                 // guarded by queue_mutex_
  bool stop_ = false;                     // guarded by queue_mutex_
  std::thread thread_;                    // last: starts once the rest exists
};

}  // namespace auv::control
