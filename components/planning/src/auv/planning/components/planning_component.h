#pragma once
// The `planning` component: the online anytime RRT* of docs/paper.md §2.2 on DDS. It keeps a
// replica of the occupancy map from `map/update` and runs a PlanningSession (the query and
// waypoint protocol, planning_session.h) in its own thread: it converts what arrives, calls
// the session and publishes what the session decides.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <Eigen/Core>

#include "auv/interfaces/component.h"
#include "auv/mapping/map_replica.h"
#include "auv/planning/planning_session.h"

namespace auv::planning {

/// Subscribes `map/update` (map), `nav/odometry` (state), `mission/query` and
/// `planner/waypoint_request` (command); publishes `planner/waypoint`, `planner/cancel`
/// (command), `planner/path` and `planner/tree` (viewing); calls `map/request_full` (Trigger)
/// when an increment does not continue the replica's version.
///
/// The protocol (repeated and early waypoint requests, cancels, the time budget) is the
/// session's; see PlanningSession.
///
/// Threading: callbacks run on the executor and only queue data (never wait for the planning
/// mutex, which would stall every component composed in the process); the planning thread applies
/// map updates, re-checks the tree and solves in slices of iteration_budget, all under that mutex
/// (the core's rule: no map update while solving).
class PlanningComponent : public interfaces::Component {
 public:
  /// The session's options (range, clearance, time budget, ...) and the wiring's own.
  struct Options : SessionOptions {
    double path_rate = 2.0;  ///< Hz, rate of planner/path.
    double tree_rate = 1.0;  ///< Hz, rate of planner/tree.
    /// s, period of map/request_full calls while the replica misses an update.
    double full_request_period = 1.0;
    std::string map_id = "octomap";     ///< OctomapUpdate.map_id this planner follows.
    std::string world_frame = "world";  ///< frame of the published poses (NED).
    /// The wiring's own fields with meaning, unit and range; the session's are in
    /// SessionOptions::table() and ClearanceOptions::table().
    static const config::OptionTable<Options>& table();
  };

  PlanningComponent();
  ~PlanningComponent() override;

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  /// Map version the replica holds (0: none yet). Thread-safe.
  uint64_t mapSequence() const { return map_sequence_; }
  /// Planning slices run since activate(). Thread-safe.
  uint64_t slices() const { return slices_; }
  /// Latest position from `nav/odometry` (none yet: nullopt). Thread-safe.
  std::optional<Eigen::Vector3d> vehiclePosition() const {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    return vehicle_position_;
  }

 private:
  void onMapUpdate(const msg::OctomapUpdate& update);
  void onOdometry(const msg::Odometry& odometry);
  void onQuery(const msg::PlannerQuery& query);
  void onWaypointRequest(const msg::WaypointRequest& request);
  void planningLoop();
  /// Planning thread, under mutex_: the queued map updates, a queued query, then the queued
  /// waypoint requests.
  void applyInbox();
  void applyMapUpdate(const msg::OctomapUpdate& update);
  /// Planning thread, under mutex_: publishes what the session decided, in order.
  void publishOutbox();
  void publishViews();
  void requestFullMapIfNeeded();
  /// s, the node's clock (the session's time).
  double now() const;

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::shared_ptr<interfaces::Subscription<msg::OctomapUpdate>> map_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PlannerQuery>> query_sub_;
  std::shared_ptr<interfaces::Subscription<msg::WaypointRequest>> request_sub_;
  std::shared_ptr<interfaces::Publisher<msg::Waypoint>> waypoint_pub_;
  std::shared_ptr<interfaces::Publisher<msg::WaypointCancel>> cancel_pub_;
  std::shared_ptr<interfaces::Publisher<msg::Path>> path_pub_;
  std::shared_ptr<interfaces::Publisher<msg::PlannerTree>> tree_pub_;
  std::shared_ptr<interfaces::Client<msg::TriggerRequest, msg::TriggerReply>> full_client_;
  std::shared_ptr<interfaces::Timer> full_request_timer_;

  // Filled by callbacks, drained by the planning thread.
  mutable std::mutex inbox_mutex_;
  std::condition_variable inbox_changed_;
  std::deque<msg::OctomapUpdate> map_inbox_;
  std::optional<msg::PlannerQuery> query_inbox_;
  std::deque<msg::WaypointRequest> request_inbox_;
  std::optional<Eigen::Vector3d> vehicle_position_;  // guarded by inbox_mutex_

  // Planning state: the planning thread, under mutex_.
  std::mutex mutex_;
  std::unique_ptr<mapping::MapReplica> replica_;  // the map from map/update
  std::unique_ptr<PlanningSession> session_;
  // The last waypoint published: a repeat is that very message again (same stamp).
  msg::Waypoint last_waypoint_;

  std::atomic<uint64_t> map_sequence_{0};
  std::atomic<bool> full_map_needed_{false};
  std::future<msg::TriggerReply> full_reply_;
  std::atomic<uint64_t> slices_{0};
  std::atomic<bool> running_{false};
  std::thread thread_;
  int64_t last_path_ns_ = 0;
  int64_t last_tree_ns_ = 0;
};

}  // namespace auv::planning
