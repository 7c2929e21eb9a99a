#include "auv/mapping/prior_map_alignment.h"

#include "auv/mapping/prior_registration.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace auv::mapping {
namespace {

using detail::Cell;
using detail::cellOf;
using detail::classify;
using detail::Fit;
using detail::kDegree;
using detail::kMinShiftM;
using detail::mainExtent;
using detail::pack;
using detail::Placement;
using detail::Registration;
using detail::thin;

constexpr std::size_t kMaxRegistrationPoints = 3000;  // thinned: the search costs O(points)
constexpr std::size_t kMaxSeabedPoints = 1000;        // for the optional depth refinement

std::string percent(double fraction) {
  std::ostringstream out;
  out.precision(3);
  out << 100.0 * fraction << " %";
  return out.str();
}

}  // namespace

const char* toString(AlignmentState state) {
  switch (state) {
    case AlignmentState::COLLECTING:
      return "COLLECTING";
    case AlignmentState::ALIGNED:
      return "ALIGNED";
    case AlignmentState::DEGENERATE:
      return "DEGENERATE";
    case AlignmentState::FAILED:
      return "FAILED";
  }
  return "?";
}

const config::OptionTable<PriorMapAlignment::Options>& PriorMapAlignment::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"min_points", &O::min_points,
       "returns (distinct map cells) collected before the first alignment attempt", "points",
       Range::closed(10, 1e7)},
      {"retry_points", &O::retry_points, "new returns between alignment attempts", "points",
       Range::closed(1, 1e7)},
      {"max_points", &O::max_points,
       "returns after which alignment gives up and the prior stays unused", "points",
       Range::closed(10, 1e8)},
      {"min_extent_m", &O::min_extent_m,
       "extent of the steep-surface returns along their main direction before an attempt", "m",
       Range::closed(0.0, 1000.0)},
      {"search_radius_m", &O::search_radius_m, "horizontal offset searched, about the submap", "m",
       Range::closed(0.0, 100.0)},
      {"search_yaw_deg", &O::search_yaw_deg, "yaw offset searched", "deg",
       Range::closed(0.0, 180.0)},
      {"min_inlier_fraction", &O::min_inlier_fraction,
       "fraction of returns within one cell of the prior's occupied cells to accept", "",
       Range::aboveUpTo(0.0, 1.0)},
      {"max_ambiguity_ratio", &O::max_ambiguity_ratio,
       "accept only if the best distinct other placement matches less than this times the best", "",
       Range::aboveUpTo(0.0, 1.0)},
      {"min_constraint", &O::min_constraint,
       "relative loss of matches a 2 m shift or turn must cause (below: degenerate)", "",
       Range::closed(0.0, 1.0)},
      {"refine_z", &O::refine_z, "also estimate a depth offset from seabed returns"},
      {"log_odds_scale", &O::log_odds_scale,
       "prior cells enter the map with this times their log-odds (new misses clear them fast)", "",
       Range::aboveUpTo(0.0, 1.0)},
  };
  return kTable;
}

void PriorMapAlignment::Options::check() const {
  config::checkOptions(*this, table(), "PriorMapAlignment: ");
  if (max_points < min_points) {
    throw std::invalid_argument("PriorMapAlignment: max_points must be >= min_points");
  }
}

/// The vehicle's returns, one mean point per cell, in arrival order.
struct PriorMapAlignment::Submap {
  std::unordered_map<uint64_t, uint32_t> index;
  std::vector<Cell> cells;
  std::vector<Eigen::Vector3d> sums;
  std::vector<uint32_t> counts;
};

/// The prior's occupied cells.
struct PriorMapAlignment::PriorIndex {
  double resolution = 0.5;
  std::unordered_set<uint64_t> occupied;
  std::vector<Cell> cells;
};

namespace {

/// Searches, refines the best peaks and judges the best: accepted (ALIGNED), no clear match
/// yet (COLLECTING) or degenerate. Fills the result's transform and measures.
AlignmentState judge(const Registration& registration, const PriorMapAlignment::Options& options,
                     AlignmentResult& result, std::ostringstream& reason) {
  std::vector<Fit> fits;
  for (const Placement& peak :
       registration.coarseSearch(options.search_radius_m, options.search_yaw_deg * kDegree)) {
    fits.push_back(registration.refine(peak, options.refine_z));
  }
  std::sort(fits.begin(), fits.end(),
            [](const Fit& a, const Fit& b) { return a.inlier_fraction > b.inlier_fraction; });
  const Fit& best = fits.front();
  double second = 0.0;  // ICP may pull a peak onto the best: only distinct ones count
  const Fit* rival = nullptr;
  for (std::size_t k = 1; k < fits.size(); ++k) {
    if (registration.distance(fits[k].placement, best.placement) <= kMinShiftM) continue;
    if (fits[k].inlier_fraction > second) {
      second = fits[k].inlier_fraction;
      rival = &fits[k];
    }
  }
  const Eigen::Isometry3d navigation_T_prior = registration.isometry(best.placement).inverse();
  result.navigation_T_prior = navigation_T_prior;
  result.x_m = navigation_T_prior.translation().x();
  result.y_m = navigation_T_prior.translation().y();
  result.z_m = navigation_T_prior.translation().z();
  result.yaw_rad = std::atan2(navigation_T_prior.linear()(1, 0), navigation_T_prior.linear()(0, 0));
  result.inlier_fraction = best.inlier_fraction;
  result.rms_m = best.rms;
  result.ambiguity_ratio = best.inlier_fraction > 0.0 ? second / best.inlier_fraction : 0.0;
  result.constraint = registration.constraint(best);
  reason.precision(3);
  if (best.inlier_fraction < options.min_inlier_fraction) {
    reason << "the best placement matches " << percent(best.inlier_fraction)
           << " of the returns (min_inlier_fraction " << options.min_inlier_fraction << ")";
    return AlignmentState::COLLECTING;
  }
  if (result.constraint < options.min_constraint) {
    reason << "degenerate: shifting the best placement by " << kMinShiftM
           << " m (or turning it by that arc) loses only " << percent(result.constraint)
           << " of its matches (min_constraint " << options.min_constraint
           << "): the returns do not fix x, y and yaw (a straight wall?)";
    return AlignmentState::DEGENERATE;
  }
  if (result.ambiguity_ratio > options.max_ambiguity_ratio) {
    const Eigen::Vector2d offset(rival->placement.tx - best.placement.tx,
                                 rival->placement.ty - best.placement.ty);
    reason << "ambiguous: a placement " << offset.norm() << " m and "
           << (rival->placement.yaw - best.placement.yaw) / kDegree << " deg away matches "
           << result.ambiguity_ratio << " times as many returns (max_ambiguity_ratio "
           << options.max_ambiguity_ratio << ")";
    return AlignmentState::COLLECTING;
  }
  reason << "matches " << percent(best.inlier_fraction) << " of " << registration.size()
         << " returns, RMS " << best.rms << " m, next distinct placement " << result.ambiguity_ratio
         << " of that, constraint " << result.constraint;
  return AlignmentState::ALIGNED;
}

}  // namespace

PriorMapAlignment::PriorMapAlignment(std::unique_ptr<octomap::OcTree> prior, const Options& options)
    : options_(options),
      prior_(std::move(prior)),
      index_(std::make_unique<PriorIndex>()),
      submap_(std::make_unique<Submap>()) {
  options_.check();
  if (!prior_) throw std::invalid_argument("PriorMapAlignment: no prior map");
  const double resolution = prior_->getResolution();
  index_->resolution = resolution;
  // Cell index = key - the key of coordinate 0 (OctoMap: floor(coordinate / resolution)).
  const int zero_key = prior_->coordToKey(0.0);
  const unsigned max_depth = prior_->getTreeDepth();
  for (auto it = prior_->begin_leafs(), end = prior_->end_leafs(); it != end; ++it) {
    if (!prior_->isNodeOccupied(*it)) continue;
    const octomap::OcTreeKey key = it.getKey();
    const Cell cell(key[0] - zero_key, key[1] - zero_key, key[2] - zero_key);
    // A coarse leaf stands for all the finest cells it covers (its key is their centre key).
    const int half = it.getDepth() == max_depth ? 0 : 1 << (max_depth - it.getDepth() - 1);
    for (int dx = -half; dx < std::max(half, 1); ++dx) {
      for (int dy = -half; dy < std::max(half, 1); ++dy) {
        for (int dz = -half; dz < std::max(half, 1); ++dz) {
          const Cell c = cell + Cell(dx, dy, dz);
          if (index_->occupied.insert(pack(c)).second) index_->cells.push_back(c);
        }
      }
    }
  }
  next_attempt_at_ = static_cast<std::size_t>(options_.min_points);
  result_.reason =
      "collecting returns (" + std::to_string(options_.min_points) + " before the first attempt)";
}

PriorMapAlignment::~PriorMapAlignment() = default;

std::size_t PriorMapAlignment::pointsCollected() const {
  return submap_ ? submap_->cells.size() : result_.points_collected;
}

void PriorMapAlignment::addReturn(const Eigen::Vector3d& point) {
  if (result_.finished || !point.allFinite()) return;
  const Cell cell = cellOf(point, index_->resolution);
  const auto [it, added] =
      submap_->index.emplace(pack(cell), static_cast<uint32_t>(submap_->cells.size()));
  if (added) {
    submap_->cells.push_back(cell);
    submap_->sums.push_back(point);
    submap_->counts.push_back(1);
  } else {
    submap_->sums[it->second] += point;
    ++submap_->counts[it->second];
  }
}

bool PriorMapAlignment::attemptDue() const {
  if (result_.finished) return false;
  const std::size_t limit = static_cast<std::size_t>(options_.max_points);
  return submap_->cells.size() >= std::min(next_attempt_at_, limit);
}

const AlignmentResult& PriorMapAlignment::attempt() {
  if (result_.finished) return result_;
  const std::size_t collected = submap_->cells.size();
  ++result_.attempts;
  result_.points_collected = collected;
  next_attempt_at_ = collected + static_cast<std::size_t>(options_.retry_points);
  const double resolution = index_->resolution;

  std::vector<Eigen::Vector3d> means(collected);
  for (std::size_t i = 0; i < collected; ++i) {
    means[i] = submap_->sums[i] / static_cast<double>(submap_->counts[i]);
  }
  std::vector<Eigen::Vector3d> structure, seabed;
  classify(submap_->cells, means, &structure, &seabed);
  const std::size_t min_structure = std::max<std::size_t>(10, options_.min_points / 4);
  const double extent = mainExtent(structure);
  std::ostringstream reason;
  AlignmentState state = AlignmentState::COLLECTING;
  if (structure.size() < min_structure) {
    state = AlignmentState::DEGENERATE;
    reason << "only " << structure.size() << " of " << collected
           << " returns lie on steep surfaces (need " << min_structure
           << "): seabed returns fix depth only";
  } else if (extent < options_.min_extent_m) {
    reason << "steep-surface returns span " << extent << " m (min_extent_m "
           << options_.min_extent_m << ")";
  } else {
    Registration registration(thin(structure, kMaxRegistrationPoints),
                              thin(seabed, kMaxSeabedPoints), resolution);
    result_.points_used = registration.size();
    if (!registration.buildGrid(index_->cells, options_.search_radius_m,
                                options_.refine_z ? 2.0 : 0.0)) {
      state = AlignmentState::FAILED;
      result_.finished = true;
      reason << "the returns and the search around them span more cells than a 64 MB grid "
                "holds: align from fewer returns (prior_min_points, prior_retry_points)";
    } else {
      state = judge(registration, options_, result_, reason);
    }
  }
  result_.state = state;
  if (state == AlignmentState::ALIGNED) {
    result_.finished = true;
  } else if (!result_.finished && collected >= static_cast<std::size_t>(options_.max_points)) {
    result_.finished = true;
    if (state != AlignmentState::DEGENERATE) result_.state = AlignmentState::FAILED;
    result_.reason = "gave up after " + std::to_string(collected) +
                     " returns (max_points), the prior stays unused: " + reason.str();
  }
  if (!result_.finished || result_.state == AlignmentState::ALIGNED) {
    result_.reason = reason.str();
  }
  if (result_.finished) submap_ = std::make_unique<Submap>();  // free it: no more attempts
  return result_;
}

}  // namespace auv::mapping
