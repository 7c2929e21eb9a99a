#pragma once
// Relocalising against a prior map before trusting it (issue 21): a repeat mission starts from
// an earlier visit's map, but its navigation frame differs from that visit's (start offset,
// drift). PriorMapAlignment holds the prior aside, collects the vehicle's own returns (in the
// navigation frame) into a submap and registers the submap to the prior's occupied cells:
// a coarse search over horizontal offset and yaw, then a robust ICP. Depth (pressure sensor)
// and roll/pitch (AHRS) are trusted, so only x, y and yaw are searched (z optionally refined).
// The result is accepted only when it is unambiguous and the geometry constrains it; otherwise
// it keeps collecting, and reports why. No DDS: the mapping component feeds it.
//
// Returns on near-horizontal surfaces (seabed, boulder tops) fix depth only, which the pressure
// sensor gives already; they would match the prior's seabed at every horizontal offset and so
// inflate every placement's score. Registration uses the other returns ("structure": walls,
// boulder flanks), told apart by the normal of each submap cell's neighbourhood.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/config/option_table.h"

namespace auv::mapping {

enum class AlignmentState {
  COLLECTING,  ///< not enough evidence yet, or no clear match yet: keeps collecting
  ALIGNED,     ///< the transform is found and trusted (final)
  DEGENERATE,  ///< the returns do not constrain x, y and yaw (one straight wall, seabed only);
               ///< final once max_points is reached, otherwise still collecting
  FAILED,      ///< max_points reached without a trusted match: the prior stays unused (final)
};
const char* toString(AlignmentState state);

struct AlignmentResult {
  AlignmentState state = AlignmentState::COLLECTING;
  bool finished = false;  ///< ALIGNED, or given up after max_points: no more attempts
  /// Prior-frame coordinates -> navigation frame (rotation about z, then translation).
  Eigen::Isometry3d navigation_T_prior = Eigen::Isometry3d::Identity();
  double x_m = 0.0, y_m = 0.0, z_m = 0.0, yaw_rad = 0.0;  ///< navigation_T_prior's parts
  /// Fraction of the registered returns within one cell of an occupied prior cell centre.
  double inlier_fraction = 0.0;
  double rms_m = 0.0;  ///< RMS distance of the inliers to their prior cell centres
  /// Inlier fraction of the best distinct other placement over the best's (0: none found).
  double ambiguity_ratio = 0.0;
  /// Smallest relative loss of inlier fraction when the solution is shifted by 2 m in any
  /// horizontal direction or turned by the same arc: near 0 along a ridge (degenerate).
  double constraint = 0.0;
  std::size_t points_used = 0;       ///< structure returns registered (after thinning)
  std::size_t points_collected = 0;  ///< distinct map cells holding returns
  int attempts = 0;
  std::string reason;  ///< one line: why this state
};

class PriorMapAlignment {
 public:
  /// Meaning, unit and range of each field: table() (prior_map_alignment.cc); the mapping
  /// component declares them with the prefix "prior_".
  struct Options {
    int64_t min_points = 500;    ///< returns (distinct cells) before the first attempt
    int64_t retry_points = 250;  ///< new returns between attempts
    int64_t max_points = 40000;  ///< give up (FAILED / DEGENERATE) at this many
    double min_extent_m = 8.0;   ///< structure returns' extent along their main direction
    double search_radius_m = 5.0;
    double search_yaw_deg = 10.0;
    double min_inlier_fraction = 0.6;
    double max_ambiguity_ratio = 0.85;
    double min_constraint = 0.1;
    bool refine_z = false;        ///< also estimate a depth offset (seabed returns)
    double log_odds_scale = 0.5;  ///< prior cells enter the map with this times their log-odds
    static const config::OptionTable<Options>& table();
    /// Throws std::invalid_argument naming the field (a range of table(), or max_points <
    /// min_points).
    void check() const;
  };

  /// `prior`: the earlier visit's map (its frame is "prior"); the submap uses its resolution.
  PriorMapAlignment(std::unique_ptr<octomap::OcTree> prior, const Options& options);
  ~PriorMapAlignment();

  /// A return (surface point) of the vehicle's own sonar, navigation frame. Ignored once
  /// finished.
  void addReturn(const Eigen::Vector3d& point);
  /// Enough new returns for an attempt (min_points, then every retry_points) and not finished.
  bool attemptDue() const;
  /// Registers the submap collected so far to the prior and updates result() (can take a
  /// second on a large submap). Frees the submap once finished.
  const AlignmentResult& attempt();
  const AlignmentResult& result() const { return result_; }
  const octomap::OcTree& prior() const { return *prior_; }
  const Options& options() const { return options_; }
  std::size_t pointsCollected() const;

 private:
  struct Submap;
  struct PriorIndex;
  Options options_;
  std::unique_ptr<octomap::OcTree> prior_;
  std::unique_ptr<PriorIndex> index_;  // occupied prior cells, dilated by one cell
  std::unique_ptr<Submap> submap_;
  std::size_t next_attempt_at_ = 0;  // points collected
  AlignmentResult result_;
};

}  // namespace auv::mapping
