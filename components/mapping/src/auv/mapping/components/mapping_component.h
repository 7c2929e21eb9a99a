#pragma once
// The `mapping` component: builds the occupancy map from sonar beams (and point clouds) placed
// with the odometry pose interpolated at each measurement's stamp, and publishes it on
// `map/update` as FULL maps and exact INCREMENTAL diffs (formats in map_builder.h, README.md).

#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "auv/interfaces/component.h"
#include "auv/mapping/map_builder.h"
#include "auv/mapping/navigation_jump.h"
#include "auv/mapping/pose_buffer.h"
#include "auv/mapping/prior_map_alignment.h"

namespace auv::mapping {

/// Subscribes `sonar/beam`, `sonar/scan` (multibeam swaths), `dvl/beams` (the DVL's bottom
/// returns; both point clouds, sensor data) and `nav/odometry` (state); publishes
/// `map/update` (map profile: reliable, transient local); serves `map/save` (SaveMapRequest),
/// `map/clear` and `map/request_full` (Trigger).
///
/// Late joiners: the transient-local history (keep last 2) holds only the latest updates,
/// which may be increments they cannot apply; so a FULL also goes out on the first tick after
/// the number of matched readers grows, and stays the latest sample for late_joiner_hold. FULLs
/// also go out at start, every full_map_period, after map/clear and on map/request_full. A
/// FULL is the version (sequence number and stamp) of the update before it, pending changes
/// going out first as an increment, so readers that hold that version skip it (MapReplica);
/// only a clear makes a FULL a new version.
///
/// A navigation jump (a reset of the estimate by more than the motion explains) moves the map
/// with it, so the returns before and after it agree; a FULL follows (README "Navigation jumps").
///
/// initial_map (align_initial_map): held aside until the vehicle's own returns align with it
/// (PriorMapAlignment, README "Prior maps"); then moved into the map, at prior_log_odds_scale of
/// its confidence, and a FULL follows. Each attempt goes to the log and prior_alignment.json.
class MappingComponent : public interfaces::Component {
 public:
  struct Options {
    MapBuilder::Options map;
    PoseBuffer::Options poses;
    double update_rate = 2.0;       ///< Hz, rate of map/update increments.
    double full_map_period = 10.0;  ///< s, period of FULL maps.
    /// s, after a new reader matches, how long the FULL sent for it stays the newest sample of
    /// the transient-local history (increments wait, changes accumulate). Covers
    /// the reader discovering the writer after the writer discovered the reader.
    double late_joiner_hold = 2.0;
    std::string map_id = "octomap";     ///< OctomapUpdate.map_id (DDS key).
    std::string world_frame = "world";  ///< frame of odometry and of the map (NED).
    std::string map_directory = ".";    ///< where map/save writes (relative names only).
    /// A .bt map to start from (map/save's format, same resolution), e.g. the map of an
    /// earlier mission at the site; empty: start with an empty map. map/clear empties it too.
    std::string initial_map;
    /// Hold initial_map aside until the vehicle's own returns align with it (README, "Prior
    /// maps"); false: the map from the start, trusted as it is (a map in this run's frame).
    bool align_initial_map = true;
    /// The alignment's settings, declared with the prefix "prior_".
    PriorMapAlignment::Options prior;
    /// Navigation jumps (navigation_jump.h), declared with the prefix "navigation_".
    NavigationJumpDetector::Options navigation;
    /// Beams newer than the latest odometry wait for it; at most this many.
    int64_t beam_queue_length = 500;
    /// Body-frame clouds newer than the latest odometry wait for it; at most this many.
    int64_t cloud_queue_length = 50;
    /// s (node clock), how often the map is checkpointed to map_directory while it changes,
    /// for a mapping restarted within the same launch to start from (0: never).
    double checkpoint_period = 30.0;
    /// The component's own fields (rates, names, queue) with meaning, unit and range; the
    /// map's and the pose buffer's are in their own tables.
    static const config::OptionTable<Options>& table();
  };

  void configure(interfaces::Node& node) override;
  void activate() override;
  void deactivate() override;
  void cleanup() override;

  const MapBuilder& builder() const { return *builder_; }
  uint64_t beamsInserted() const { return beams_inserted_; }
  uint64_t beamsDropped() const { return beams_dropped_; }
  uint64_t cloudsInserted() const { return clouds_inserted_; }
  /// Clouds whose pose could not be looked up (not in world_frame, odometry not covering).
  uint64_t cloudsDropped() const { return clouds_dropped_; }
  uint64_t sequenceNumber() const { return sequence_number_; }
  /// Navigation jumps the map was moved with.
  uint64_t navigationJumps() const { return navigation_jumps_; }
  /// The prior map alignment's latest result; nullptr without one (no initial_map, or
  /// align_initial_map false).
  const AlignmentResult* priorAlignment() const {
    return prior_alignment_ ? &*prior_alignment_ : nullptr;
  }

 private:
  void onBeam(const msg::SonarBeam& beam);
  void onCloud(const msg::PointCloud& cloud);
  void onOdometry(const msg::Odometry& odometry);
  /// map/save: writes the map under map_directory (relative names only).
  void onSave(const msg::SaveMapRequest& request, msg::SaveMapReply& reply);
  /// What a beam waiting for odometry needs (not the message: no copy of its bins).
  struct PendingBeam {
    int64_t stamp_ns = 0;
    BeamGeometry geometry;       ///< sonar head frame
    Eigen::Isometry3d mounting;  ///< head -> body
  };
  /// Inserts the beam if its pose is known; false if it must wait for newer odometry.
  bool tryInsertBeam(const PendingBeam& beam);
  /// A body-frame cloud waiting for odometry: its points and ray origin in the body frame.
  struct PendingCloud {
    int64_t stamp_ns = 0;
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d origin;
    double max_range = 0.0;
  };
  /// Inserts the cloud if its pose is known; false if it must wait for newer odometry.
  bool tryInsertCloud(const PendingCloud& cloud);
  /// Inserts points given in the world frame.
  void insertWorldCloud(int64_t stamp_ns, const std::vector<Eigen::Vector3d>& points,
                        const Eigen::Vector3d& origin, double max_range);
  void tick();
  /// Moves the map by `jump` (world frame) after the navigation jumped at `stamp_ns`.
  void followNavigationJump(const Eigen::Vector3d& jump, int64_t stamp_ns);
  /// Loads initial_map: into the map, or aside for the alignment (align_initial_map).
  void loadInitialMap();
  /// Names this launch's checkpoint (none outside a launch) and starts from it when it exists
  /// (a restart); true if it did.
  bool loadCheckpoint();
  /// Writes the checkpoint when due and the map changed; a failure is logged, never fatal.
  void checkpointIfDue(int64_t now_ns);
  /// Feeds returns (world frame) to the alignment while it collects.
  void collectReturn(const Eigen::Vector3d& point);
  /// An alignment attempt: logs and records it; once ALIGNED, the prior enters the map.
  void attemptAlignment();
  /// Writes prior_alignment.json into map_directory.
  void recordAlignment(const AlignmentResult& result) const;
  void publishFull();
  void publishIncrement();
  void fillCommon(msg::OctomapUpdate& update) const;

  interfaces::Node* node_ = nullptr;
  Options options_;
  std::unique_ptr<MapBuilder> builder_;
  std::unique_ptr<PoseBuffer> poses_;
  std::unique_ptr<NavigationJumpDetector> jumps_;
  std::unique_ptr<PriorMapAlignment> aligner_;  // while it may still align
  std::optional<AlignmentResult> prior_alignment_;
  std::deque<PendingBeam> waiting_beams_;
  std::deque<PendingCloud> waiting_clouds_;
  std::shared_ptr<interfaces::Subscription<msg::SonarBeam>> beam_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PointCloud>> cloud_sub_;
  std::shared_ptr<interfaces::Subscription<msg::PointCloud>> dvl_beams_sub_;
  std::shared_ptr<interfaces::Subscription<msg::Odometry>> odometry_sub_;
  std::shared_ptr<interfaces::Publisher<msg::OctomapUpdate>> update_pub_;
  std::shared_ptr<interfaces::Service<msg::SaveMapRequest, msg::SaveMapReply>> save_srv_;
  std::shared_ptr<interfaces::Service<msg::TriggerRequest, msg::TriggerReply>> clear_srv_;
  std::shared_ptr<interfaces::Service<msg::TriggerRequest, msg::TriggerReply>> full_srv_;
  std::shared_ptr<interfaces::Timer> timer_;
  uint64_t sequence_number_ = 0;
  int64_t newest_stamp_ns_ = 0;            // newest measurement in the map
  int64_t last_full_ns_ = 0;               // node clock at the last FULL
  std::filesystem::path checkpoint_path_;  // this launch's (empty outside a launch: none)
  int64_t last_checkpoint_ns_ = 0;         // node clock at the last checkpoint
  uint64_t checkpoint_version_ = 0;        // builder version written in it
  std::string checkpoint_error_;           // the last failure, logged once
  int64_t hold_increments_until_ns_ = 0;   // node clock; see Options::late_joiner_hold
  bool full_due_ = true;          // FULL on the next tick (start, clear, request, new reader)
  int64_t version_stamp_ns_ = 0;  // newest data in the version published last (its stamp)
  bool map_replaced_ = true;      // no version published yet of the map as it is (start, clear)
  int matched_readers_ = 0;
  uint64_t beams_inserted_ = 0;
  uint64_t beams_dropped_ = 0;
  uint64_t clouds_inserted_ = 0;
  uint64_t clouds_dropped_ = 0;
  uint64_t navigation_jumps_ = 0;
};

}  // namespace auv::mapping
