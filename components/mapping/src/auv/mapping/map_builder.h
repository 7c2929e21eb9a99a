#pragma once
// Occupancy mapping from sonar beams and point clouds into an octomap::OcTree, with exact
// incremental diffs for replicas (other processes) and immutable snapshots for in-process
// readers.
//
// Diff format (OctomapUpdate INCREMENTAL, encoding OCTOMAP_ENCODING_FULL): an OctoMap `.ot`
// stream (AbstractOcTree::write) of an OcTree with the builder's resolution holding only the
// cells whose log-odds changed since the previous diff, each at its current log-odds value in
// the builder. Cells are stored at the finest depth; eight sibling cells with equal values may
// be stored as one coarser leaf, which stands for all eight. To apply: for each leaf of the diff,
// set every finest-depth cell it covers in the replica to the leaf's log-odds (applyDiff()).
// The replica then holds exactly the builder's log-odds. Deleting cells is not expressible:
// after clear() the next update must be FULL.
//
// Snapshot design: OctoMap is not thread-safe, so readers never touch the live tree. The
// builder (one writer thread) copies the tree into a `std::shared_ptr<const OcTree>` and swaps
// it in atomically; readers call snapshot() from any thread and keep a complete, immutable
// version for as long as they hold the pointer: never a lock on the reader's side, and the
// planner can iterate a snapshot for as long as it likes. A copy costs O(tree size) (about
// 0.3 s for 1.8 M nodes, mapping_bench), so copies are made for readers only: snapshot() asks
// for one, and refreshSnapshot() (the component calls it at update_rate) copies only if a reader
// asked since the last copy and the map changed. A reader polling snapshot() thus sees a map at
// most one poll period plus one update period old; its first call may return an older one.

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/config/option_table.h"
#include "auv/mapping/changed_cells.h"

namespace auv::mapping {

/// One sonar beam in its sensor frame: a ray along `direction` from the sensor origin.
struct BeamGeometry {
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  ///< unit vector, sensor frame
  double min_range = 0.0;   ///< m, blanking distance: no information closer than this
  double max_range = 20.0;  ///< m, farthest range measured
  /// m, range of the (first) return; nullopt: no echo, the beam is free up to max_range.
  std::optional<double> return_range;
};

/// Sonar beam direction in the sonar head frame for head angle `beam_angle_rad` about its
/// z axis (0 = x axis, positive turns x towards y).
Eigen::Vector3d beamDirection(double beam_angle_rad);

/// Counts of one insertion.
struct InsertStats {
  std::size_t free_cells = 0;      ///< cells updated as free (miss)
  std::size_t occupied_cells = 0;  ///< cells updated as occupied (hit)
};

class MapBuilder {
 public:
  /// Probability defaults are OctoMap's own, so a replica built as a plain OcTree (e.g. from a
  /// FULL update) clamps the same way as the builder.
  /// Meaning, unit and range of each number: table() (map_builder.cc), declared once.
  struct Options {
    double resolution = 0.5;  ///< 0.5 m suits a 20 m sonar.
    double prob_hit = 0.7;
    double prob_miss = 0.4;
    /// Keeps cells able to become occupied again after long free evidence.
    double clamping_min = 0.1192;
    double clamping_max = 0.971;
    double occupancy_threshold = 0.5;
    /// A beam without an echo clears cells only up to the first one the map holds occupied,
    /// that one included (one miss: isolated false returns still fade). Why: a beam grazing a
    /// wall returns too weak an echo to detect, and its single-ray model would otherwise run on
    /// through the wall and erase it (walls beside the vehicle vanish). Beams with an echo
    /// still clear through occupied cells, which removes stale copies of walls left by
    /// navigation drift.
    bool no_return_stops_at_occupied = true;
    /// The fields with meaning, unit and range: check() and the mapping component's
    /// parameters (so `auv run mapping --help`) come from it.
    static const config::OptionTable<Options>& table();
    /// Throws std::invalid_argument naming the bad field: a range of table(), or the clamps
    /// and threshold against the probabilities (clamping_min <= prob_miss, clamping_max >=
    /// prob_hit, occupancy_threshold between the clamps).
    void check() const;
  };

  MapBuilder() : MapBuilder(Options{}) {}
  explicit MapBuilder(const Options& options);

  /// Integrates one beam seen from `world_T_sensor` (sensor frame -> world): cells from the
  /// beam's min_range up to the return get a miss, the cell at the return a hit; with no
  /// return, cells up to max_range get a miss only (or up to the first occupied cell, see
  /// Options::no_return_stops_at_occupied). The return's cell is never also updated as
  /// free (occupied wins, as in OcTree::insertPointCloud). Keys come from computeRayKeys and
  /// are updated with updateNode rather than through insertPointCloud so that the builder knows
  /// every cell it touched (OctoMap's own change detection only reports occupancy flips, not
  /// log-odds changes, which exact diffs need); the cell updates are the same.
  InsertStats insertBeam(const BeamGeometry& beam, const Eigen::Isometry3d& world_T_sensor);
  /// The world point of the beam's return as insertBeam() marks it occupied; nullopt for a beam
  /// without an echo in [min_range, max_range]. (Feeds PriorMapAlignment with what the map
  /// takes as surface.)
  static std::optional<Eigen::Vector3d> returnPoint(const BeamGeometry& beam,
                                                    const Eigen::Isometry3d& world_T_sensor);

  /// Integrates returns `points_world` (world frame) seen from `origin_world`, like
  /// OcTree::insertPointCloud(cloud, origin, max_range): rays longer than `max_range` (> 0)
  /// clear free space only up to max_range; max_range <= 0 means unlimited. Each cell is updated
  /// at most once per cloud, occupied winning over free.
  InsertStats insertCloud(const std::vector<Eigen::Vector3d>& points_world,
                          const Eigen::Vector3d& origin_world, double max_range);
  /// True when insertCloud() marks `point` occupied (a return): within max_range of the
  /// origin, or max_range <= 0.
  static bool isReturn(const Eigen::Vector3d& point, const Eigen::Vector3d& origin_world,
                       double max_range) {
    return max_range <= 0.0 || (point - origin_world).norm() <= max_range;
  }

  /// Adds the cells of `prior` (another map at the same resolution, e.g. an earlier visit's)
  /// moved by `map_T_prior` into cells this map does not hold yet: cells the map already holds
  /// keep their own evidence. Each new cell takes `log_odds_scale` times the prior cell's
  /// log-odds (less confident than the vehicle's own returns, so that misses clear stale prior
  /// content quickly). Each map cell samples the prior cell under its centre (no holes where
  /// the rotation spreads cells apart). Tracked as changes like any insertion.
  InsertStats insertPrior(const octomap::OcTree& prior, const Eigen::Isometry3d& map_T_prior,
                          double log_odds_scale);

  /// Starts (or stops) recording which cells change, for takeDiff(). Off by default.
  void enableChangeTracking(bool enable);
  bool changeTrackingEnabled() const { return track_changes_; }
  /// Cells changed since the last takeDiff()/clear().
  std::size_t pendingChangeCount() const { return changed_.size(); }
  /// Serializes the pending changes (format above) into `data`, returns the number of cells
  /// and the world box holding them (min > max when none); forgets the pending changes.
  struct Diff {
    std::string data;
    std::size_t cell_count = 0;
    Eigen::Vector3d changed_min = Eigen::Vector3d::Constant(1.0);
    Eigen::Vector3d changed_max = Eigen::Vector3d::Constant(-1.0);
  };
  Diff takeDiff();
  /// Applies a diff written by takeDiff() to `replica` (same resolution). Throws
  /// std::runtime_error, the replica unchanged, when the data is not an OcTree stream, the
  /// resolution differs or its leaves cover more than kMaxDiffCells finest cells.
  static void applyDiff(const std::string& data, octomap::OcTree& replica);
  /// Most finest cells one diff may set (a 50 m cube at 0.5 m; an update covers a few sonar
  /// sweeps).
  static constexpr uint64_t kMaxDiffCells = uint64_t{1} << 20;

  /// The whole map as OcTree::writeBinaryConst writes it (.bt: maximum-likelihood only).
  std::string fullBinary() const;
  /// The whole map as AbstractOcTree::write writes it (.ot: with log-odds).
  std::string fullWithProbabilities() const;
  /// Writes the map as a .bt file; false on an I/O error.
  bool save(const std::string& path) const;
  /// Empties the map and the pending changes.
  void clear();
  /// Replaces the map with a .bt file (save()'s format: occupied and free cells at the clamping
  /// bounds), e.g. the map of an earlier mission at the same site, or an .ot file
  /// (fullWithProbabilities(): every cell's log-odds, a checkpoint); drops the pending changes.
  /// Throws std::runtime_error naming the file when it cannot be read or holds another
  /// resolution; the map is then unchanged.
  void load(const std::string& path);

  /// Counts the changes of the live tree (a checkpoint is due only when it moved).
  uint64_t version() const { return version_; }
  /// Copies the live tree into a new immutable snapshot and publishes it (writer thread only).
  std::shared_ptr<const octomap::OcTree> takeSnapshot();
  /// takeSnapshot() if snapshot() was called since the last copy and the map changed since;
  /// true if it copied (writer thread only).
  bool refreshSnapshot();
  /// The latest published snapshot (never null), and a request for a fresh one at the next
  /// refreshSnapshot(); callable from any thread.
  std::shared_ptr<const octomap::OcTree> snapshot() const;

  /// The live tree: only for the writer thread.
  const octomap::OcTree& tree() const { return tree_; }
  const Options& options() const { return options_; }
  /// Integration counters since construction.
  uint64_t beamsInserted() const { return beams_inserted_; }
  uint64_t cellUpdates() const { return cell_updates_; }

 private:
  InsertStats integrate(const octomap::KeySet& free_keys, const octomap::KeySet& occupied_keys);
  /// updateNode without touching inner nodes (lazy), noting the cell's new log-odds for the
  /// next diff and the cell for settleInnerNodes().
  void update(const octomap::OcTreeKey& key, bool occupied);
  /// OcTree::updateNode(key, occupied, lazy_eval = true) in one descent from the root where
  /// OctoMap makes two (its early-abort search, then the update): the same nodes created,
  /// expanded and updated. Returns the updated cell, or the clamped node left alone.
  octomap::OcTreeNode* updateLazily(const octomap::OcTreeKey& key, bool occupied);
  /// Brings the inner nodes above the cells update() touched to what OctoMap's eager
  /// updateNode leaves (maximum of the children, collapsible nodes pruned), deepest first:
  /// the same tree, byte for byte, but each inner node is settled once per beam or cloud
  /// instead of once per cell (consecutive cells of a ray share all but the last levels).
  void settleInnerNodes();
  void configureTree(octomap::OcTree& tree) const;

  Options options_;
  octomap::OcTree tree_;
  bool track_changes_ = false;
  // Changed cells with their log-odds, noted when updated: a diff then needs no tree search
  // (updateNode returns the leaf, or its pruned parent, which holds the same value).
  detail::ChangedCells changed_;
  octomap::KeyRay ray_scratch_;
  std::vector<octomap::OcTreeKey> touched_;  // cells updated since the last settleInnerNodes()
  std::vector<std::pair<uint64_t, octomap::OcTreeKey>> touched_codes_;  // scratch: sorting them
  octomap::KeySet free_scratch_;
  octomap::KeySet occupied_scratch_;
  std::shared_ptr<const octomap::OcTree> snapshot_;   // accessed with std::atomic_load/store
  mutable std::atomic<bool> snapshot_wanted_{false};  // set by readers in snapshot()
  uint64_t version_ = 0;                              // counts changes of the live tree
  uint64_t snapshot_version_ = 0;                     // version_ at the last copy
  uint64_t beams_inserted_ = 0;
  uint64_t cell_updates_ = 0;
};

}  // namespace auv::mapping
