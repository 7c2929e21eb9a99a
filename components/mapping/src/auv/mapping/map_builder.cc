#include "auv/mapping/map_builder.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "auv/mapping/ot_stream.h"

namespace auv::mapping {
namespace {

octomap::point3d toPoint(const Eigen::Vector3d& v) {
  return octomap::point3d(static_cast<float>(v.x()), static_cast<float>(v.y()),
                          static_cast<float>(v.z()));
}

bool hasReturn(const BeamGeometry& beam) {
  const double min_range = std::max(0.0, beam.min_range);
  return beam.return_range && *beam.return_range >= min_range &&
         *beam.return_range <= beam.max_range;
}

void requireRange(bool ok, const char* message) {
  if (!ok) throw std::invalid_argument(std::string("MapBuilder: ") + message);
}

}  // namespace

Eigen::Vector3d beamDirection(double beam_angle_rad) {
  return Eigen::Vector3d(std::cos(beam_angle_rad), std::sin(beam_angle_rad), 0.0);
}

const config::OptionTable<MapBuilder::Options>& MapBuilder::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"resolution", &O::resolution, "map leaf size", "m", Range::closed(0.01, 10.0)},
      {"prob_hit", &O::prob_hit, "occupancy probability of a cell with a return", "",
       Range::open(0.5, 1.0)},
      {"prob_miss", &O::prob_miss, "occupancy probability of a cell a beam passed through", "",
       Range::open(0.0, 0.5)},
      {"clamping_min", &O::clamping_min, "lower occupancy probability clamp (<= prob_miss)", "",
       Range::open(0.0, 0.5)},
      {"clamping_max", &O::clamping_max, "upper occupancy probability clamp (>= prob_hit)", "",
       Range::open(0.5, 1.0)},
      {"occupancy_threshold", &O::occupancy_threshold,
       "probability above which a cell is occupied (between the clamps)", "",
       Range::open(0.0, 1.0)},
      {"no_return_stops_at_occupied", &O::no_return_stops_at_occupied,
       "a beam without echo clears free space only up to the first occupied cell"},
  };
  return kTable;
}

void MapBuilder::Options::check() const {
  config::checkOptions(*this, table(), "MapBuilder: ");
  requireRange(clamping_min <= prob_miss, "clamping_min must be in (0, prob_miss]");
  requireRange(clamping_max >= prob_hit, "clamping_max must be in [prob_hit, 1)");
  requireRange(occupancy_threshold > clamping_min && occupancy_threshold < clamping_max,
               "occupancy_threshold must be in (clamping_min, clamping_max)");
}

MapBuilder::MapBuilder(const Options& options) : options_(options), tree_(options.resolution) {
  options_.check();
  configureTree(tree_);
  snapshot_ = std::make_shared<const octomap::OcTree>(tree_);
}

void MapBuilder::configureTree(octomap::OcTree& tree) const {
  tree.setProbHit(options_.prob_hit);
  tree.setProbMiss(options_.prob_miss);
  tree.setClampingThresMin(options_.clamping_min);
  tree.setClampingThresMax(options_.clamping_max);
  tree.setOccupancyThres(options_.occupancy_threshold);
}

void MapBuilder::update(const octomap::OcTreeKey& key, bool occupied) {
  const octomap::OcTreeNode* node = updateLazily(key, occupied);
  if (track_changes_) changed_.set(key, node->getLogOdds());
  touched_.push_back(key);
}

octomap::OcTreeNode* MapBuilder::updateLazily(const octomap::OcTreeKey& key, bool occupied) {
  octomap::OcTreeNode* node = tree_.getRoot();
  if (node == nullptr) return tree_.updateNode(key, occupied, /*lazy_eval=*/true);
  const float update = occupied ? tree_.getProbHitLog() : tree_.getProbMissLog();
  // OctoMap's early abort: a cell (or a pruned node holding it) already clamped in the
  // direction of the update is left alone, pruned nodes unexpanded.
  const auto clamped = [&](const octomap::OcTreeNode* n) {
    return (update >= 0 && n->getLogOdds() >= tree_.getClampingThresMaxLog()) ||
           (update <= 0 && n->getLogOdds() <= tree_.getClampingThresMinLog());
  };
  const int depth_max = static_cast<int>(tree_.getTreeDepth());
  bool created = false;  // below a node created by this update: nothing to expand or abort
  for (int level = depth_max - 1; level >= 0; --level) {
    const unsigned child = octomap::computeChildIdx(key, level);
    if (!tree_.nodeChildExists(node, child)) {
      if (!created && !tree_.nodeHasChildren(node)) {  // a pruned node
        if (clamped(node)) return node;
        tree_.expandNode(node);
      } else {
        tree_.createNodeChild(node, child);
        created = true;
      }
    }
    node = tree_.getNodeChild(node, child);
  }
  if (!created && clamped(node)) return node;
  tree_.updateNodeLogOdds(node, update);
  return node;
}

void MapBuilder::settleInnerNodes() {
  const unsigned depth_max = tree_.getTreeDepth();
  // Sorted once in octree (Morton) order: a key's parent at any depth keeps that order, since
  // it only clears the key's low bits and sets the same centre bit in each coordinate, so the
  // parents stay sorted and equal parents adjacent at every level. (Sorting per level was a
  // tenth of a multibeam swath's insertion, with tens of thousands of touched cells.)
  touched_codes_.clear();
  touched_codes_.reserve(touched_.size());
  for (const auto& key : touched_) touched_codes_.emplace_back(ot_stream::cellCode(key), key);
  std::sort(touched_codes_.begin(), touched_codes_.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  touched_.clear();
  for (const auto& entry : touched_codes_) touched_.push_back(entry.second);
  for (unsigned depth = depth_max; depth-- > 0;) {
    // The touched nodes' parents at `depth`: each once, deeper levels already settled.
    for (auto& key : touched_) key = tree_.adjustKeyAtDepth(key, depth);
    touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
    for (const auto& key : touched_) {
      octomap::OcTreeNode* node = depth == 0 ? tree_.getRoot() : tree_.search(key, depth);
      // A node above `depth` (pruned meanwhile) or without children has nothing to settle.
      if (node == nullptr || !tree_.nodeHasChildren(node)) continue;
      if (!tree_.pruneNode(node)) node->updateOccupancyChildren();
    }
  }
  touched_.clear();
}

InsertStats MapBuilder::integrate(const octomap::KeySet& free_keys,
                                  const octomap::KeySet& occupied_keys) {
  InsertStats stats;
  for (const octomap::OcTreeKey& key : free_keys) {
    if (occupied_keys.count(key)) continue;  // a return in the cell outweighs rays through it
    update(key, false);
    ++stats.free_cells;
  }
  for (const octomap::OcTreeKey& key : occupied_keys) {
    update(key, true);
    ++stats.occupied_cells;
  }
  settleInnerNodes();
  cell_updates_ += stats.free_cells + stats.occupied_cells;
  ++version_;
  return stats;
}

InsertStats MapBuilder::insertBeam(const BeamGeometry& beam,
                                   const Eigen::Isometry3d& world_T_sensor) {
  const Eigen::Vector3d origin = world_T_sensor.translation();
  const Eigen::Vector3d direction = (world_T_sensor.linear() * beam.direction).normalized();
  const double min_range = std::max(0.0, beam.min_range);
  const bool has_return = hasReturn(beam);
  // No return: free up to max_range, nothing occupied (the end cell itself stays unknown, as
  // for the truncated rays of OcTree::insertPointCloud).
  const double free_until = has_return ? *beam.return_range : beam.max_range;
  const Eigen::Vector3d start = origin + min_range * direction;
  const Eigen::Vector3d end = origin + free_until * direction;
  octomap::OcTreeKey hit;
  const bool hit_valid = has_return && tree_.coordToKeyChecked(toPoint(end), hit);
  ray_scratch_.reset();
  if (free_until > min_range) tree_.computeRayKeys(toPoint(start), toPoint(end), ray_scratch_);
  // One ray visits each cell once, so no key set is needed (unlike insertCloud).
  InsertStats stats;
  const bool stop_at_occupied = !has_return && options_.no_return_stops_at_occupied;
  for (const octomap::OcTreeKey& key : ray_scratch_) {
    if (hit_valid && key == hit) continue;  // a return in the cell outweighs the ray through it
    const octomap::OcTreeNode* node = stop_at_occupied ? tree_.search(key) : nullptr;
    const bool blocked = node != nullptr && tree_.isNodeOccupied(node);
    update(key, false);
    ++stats.free_cells;
    if (blocked) break;
  }
  if (hit_valid) {
    update(hit, true);
    ++stats.occupied_cells;
  }
  settleInnerNodes();
  cell_updates_ += stats.free_cells + stats.occupied_cells;
  ++beams_inserted_;
  ++version_;
  return stats;
}

std::optional<Eigen::Vector3d> MapBuilder::returnPoint(const BeamGeometry& beam,
                                                       const Eigen::Isometry3d& world_T_sensor) {
  if (!hasReturn(beam)) return std::nullopt;
  // insertBeam()'s end point, computed the same way.
  const Eigen::Vector3d direction = (world_T_sensor.linear() * beam.direction).normalized();
  return world_T_sensor.translation() + *beam.return_range * direction;
}

InsertStats MapBuilder::insertCloud(const std::vector<Eigen::Vector3d>& points_world,
                                    const Eigen::Vector3d& origin_world, double max_range) {
  free_scratch_.clear();
  occupied_scratch_.clear();
  const octomap::point3d origin = toPoint(origin_world);
  for (const Eigen::Vector3d& point : points_world) {
    const double distance = (point - origin_world).norm();
    if (isReturn(point, origin_world, max_range)) {
      if (tree_.computeRayKeys(origin, toPoint(point), ray_scratch_)) {
        free_scratch_.insert(ray_scratch_.begin(), ray_scratch_.end());
      }
      octomap::OcTreeKey key;
      if (tree_.coordToKeyChecked(toPoint(point), key)) occupied_scratch_.insert(key);
    } else {
      const Eigen::Vector3d end = origin_world + (point - origin_world) * (max_range / distance);
      if (tree_.computeRayKeys(origin, toPoint(end), ray_scratch_)) {
        free_scratch_.insert(ray_scratch_.begin(), ray_scratch_.end());
      }
    }
  }
  return integrate(free_scratch_, occupied_scratch_);
}

InsertStats MapBuilder::insertPrior(const octomap::OcTree& prior,
                                    const Eigen::Isometry3d& map_T_prior, double log_odds_scale) {
  if (std::abs(prior.getResolution() - tree_.getResolution()) > 1e-9) {
    throw std::invalid_argument("insertPrior: prior resolution " +
                                std::to_string(prior.getResolution()) + " m, the map " +
                                std::to_string(tree_.getResolution()) + " m");
  }
  // Candidate map cells: where each prior cell's centre lands, and its horizontal neighbours
  // (a yawed grid leaves some map cells without a landing centre); each then samples the prior
  // under its own centre, so every map cell inside the moved prior gets a value once.
  const Eigen::Isometry3d prior_T_map = map_T_prior.inverse();
  octomap::KeySet candidates;
  const unsigned max_depth = prior.getTreeDepth();
  const auto addLanding = [&](const octomap::OcTreeKey& prior_key) {
    const octomap::point3d c = prior.keyToCoord(prior_key);
    const Eigen::Vector3d moved = map_T_prior * Eigen::Vector3d(c.x(), c.y(), c.z());
    octomap::OcTreeKey key;
    if (!tree_.coordToKeyChecked(toPoint(moved), key)) return;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        candidates.insert(octomap::OcTreeKey(static_cast<octomap::key_type>(key[0] + dx),
                                             static_cast<octomap::key_type>(key[1] + dy), key[2]));
      }
    }
  };
  for (auto it = prior.begin_leafs(), end = prior.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey key = it.getKey();
    if (it.getDepth() == max_depth) {
      addLanding(key);
      continue;
    }
    const int half = 1 << (max_depth - it.getDepth() - 1);  // a coarse leaf: all its cells
    for (int dx = -half; dx < half; ++dx) {
      for (int dy = -half; dy < half; ++dy) {
        for (int dz = -half; dz < half; ++dz) {
          addLanding(octomap::OcTreeKey(static_cast<octomap::key_type>(key[0] + dx),
                                        static_cast<octomap::key_type>(key[1] + dy),
                                        static_cast<octomap::key_type>(key[2] + dz)));
        }
      }
    }
  }
  InsertStats stats;
  for (const octomap::OcTreeKey& key : candidates) {
    if (tree_.search(key) != nullptr) continue;  // the vehicle's own evidence stays
    const octomap::point3d c = tree_.keyToCoord(key);
    const Eigen::Vector3d source = prior_T_map * Eigen::Vector3d(c.x(), c.y(), c.z());
    const octomap::OcTreeNode* node = prior.search(source.x(), source.y(), source.z());
    if (node == nullptr) continue;
    const float scaled = static_cast<float>(log_odds_scale * node->getLogOdds());
    const octomap::OcTreeNode* cell = tree_.setNodeValue(key, scaled, /*lazy_eval=*/true);
    if (track_changes_) changed_.set(key, cell->getLogOdds());  // clamped as the tree holds it
    touched_.push_back(key);
    ++(tree_.isNodeOccupied(cell) ? stats.occupied_cells : stats.free_cells);
  }
  settleInnerNodes();
  cell_updates_ += stats.free_cells + stats.occupied_cells;
  ++version_;
  return stats;
}

void MapBuilder::enableChangeTracking(bool enable) {
  track_changes_ = enable;
  if (!enable) changed_.clear();
}

MapBuilder::Diff MapBuilder::takeDiff() {
  Diff diff;
  diff.cell_count = changed_.size();
  std::vector<ot_stream::Cell> cells;
  cells.reserve(changed_.size());
  octomap::OcTreeKey low(0xFFFF, 0xFFFF, 0xFFFF), high(0, 0, 0);  // keyToCoord is monotonic
  changed_.forEach([&](const octomap::OcTreeKey& key, float log_odds) {
    cells.push_back({ot_stream::cellCode(key), log_odds});
    for (unsigned i = 0; i < 3; ++i) {
      low[i] = std::min(low[i], key[i]);
      high[i] = std::max(high[i], key[i]);
    }
  });
  if (!changed_.empty()) {
    const double half = 0.5 * options_.resolution;
    const octomap::point3d a = tree_.keyToCoord(low), b = tree_.keyToCoord(high);
    diff.changed_min = Eigen::Vector3d(a.x(), a.y(), a.z()).array() - half;
    diff.changed_max = Eigen::Vector3d(b.x(), b.y(), b.z()).array() + half;
  }
  // What an OcTree holding these cells (setNodeValue lazily, then updateInnerOccupancy) writes.
  diff.data = ot_stream::writeCells(cells, tree_.getResolution(), tree_.getTreeDepth());
  changed_.clear();
  return diff;
}

void MapBuilder::applyDiff(const std::string& data, octomap::OcTree& replica) {
  std::istringstream stream(data);
  const std::unique_ptr<octomap::OcTree> changes = ot_stream::readTree(stream);
  if (std::abs(changes->getResolution() - replica.getResolution()) > 1e-9) {
    throw std::runtime_error("map diff resolution " + std::to_string(changes->getResolution()) +
                             " differs from the replica's " +
                             std::to_string(replica.getResolution()));
  }
  const unsigned max_depth = changes->getTreeDepth();
  // A coarser leaf stands for every finest cell below it: the root alone would be 2^48 cells
  // (a fuzzed diff kept the replica busy for minutes). Our writer sends finest cells only.
  uint64_t cells = 0;
  for (auto it = changes->begin_leafs(), end = changes->end_leafs(); it != end; ++it) {
    cells += uint64_t{1} << (3 * (max_depth - it.getDepth()));
    if (cells > kMaxDiffCells) {
      throw std::runtime_error("map diff covers more than " + std::to_string(kMaxDiffCells) +
                               " cells (a leaf at depth " + std::to_string(it.getDepth()) + " of " +
                               std::to_string(max_depth) + ")");
    }
  }
  for (auto it = changes->begin_leafs(), end = changes->end_leafs(); it != end; ++it) {
    const float log_odds = it->getLogOdds();
    const octomap::OcTreeKey key = it.getKey();
    if (it.getDepth() == max_depth) {
      replica.setNodeValue(key, log_odds);
      continue;
    }
    // A coarser leaf stands for all finest cells it covers; its key is the cell's centre key.
    const int half = 1 << (max_depth - it.getDepth() - 1);
    octomap::OcTreeKey cell;
    for (int dx = -half; dx < half; ++dx) {
      for (int dy = -half; dy < half; ++dy) {
        for (int dz = -half; dz < half; ++dz) {
          cell[0] = static_cast<octomap::key_type>(key[0] + dx);
          cell[1] = static_cast<octomap::key_type>(key[1] + dy);
          cell[2] = static_cast<octomap::key_type>(key[2] + dz);
          replica.setNodeValue(cell, log_odds);
        }
      }
    }
  }
}

std::string MapBuilder::fullBinary() const {
  std::ostringstream stream;
  tree_.writeBinaryConst(stream);
  return stream.str();
}

std::string MapBuilder::fullWithProbabilities() const { return ot_stream::writeTree(tree_); }

bool MapBuilder::save(const std::string& path) const {
  // Not OcTree::writeBinary(path): that one converts the live tree to maximum likelihood.
  std::ofstream file(path, std::ios::binary);
  if (!file) return false;
  tree_.writeBinaryConst(file);
  file.close();
  return static_cast<bool>(file);
}

void MapBuilder::clear() {
  tree_.clear();
  changed_.clear();
  ++version_;
}

void MapBuilder::load(const std::string& path) {
  // Read into a tree of our own settings first: a bad file leaves the map as it was.
  octomap::OcTree loaded(options_.resolution);
  configureTree(loaded);
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot open map file " + path);
  // `.ot` (with log-odds, a checkpoint) or `.bt` (maximum likelihood), told by the header.
  if (file.peek() == '#' && std::filesystem::path(path).extension() == ".ot") {
    std::unique_ptr<octomap::OcTree> read;
    try {
      read = ot_stream::readTree(file);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(path + " is not an OctoMap .ot file: " + error.what());
    }
    if (std::abs(read->getResolution() - options_.resolution) > 1e-9) {
      throw std::runtime_error(path + " has resolution " + std::to_string(read->getResolution()) +
                               " m, the map " + std::to_string(options_.resolution) + " m");
    }
    // Its cells keep their log-odds; new evidence is clamped by our settings.
    loaded.swapContent(*read);
  } else {
    try {
      ot_stream::readBinaryTree(file, loaded);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(path + " is not an OctoMap binary (.bt) file: " + error.what());
    }
  }
  if (std::abs(loaded.getResolution() - options_.resolution) > 1e-9) {
    throw std::runtime_error(path + " has resolution " + std::to_string(loaded.getResolution()) +
                             " m, the map " + std::to_string(options_.resolution) + " m");
  }
  tree_.clear();  // also marks the metric bounds stale, which swapContent does not
  tree_.swapContent(loaded);
  changed_.clear();
  ++version_;
  takeSnapshot();
}

std::shared_ptr<const octomap::OcTree> MapBuilder::takeSnapshot() {
  auto copy = std::make_shared<const octomap::OcTree>(tree_);
  std::atomic_store(&snapshot_, copy);
  snapshot_version_ = version_;
  return copy;
}

bool MapBuilder::refreshSnapshot() {
  // The flag stays set until a copy is made: a request while nothing changed waits for a change.
  if (version_ == snapshot_version_ || !snapshot_wanted_.exchange(false)) return false;
  takeSnapshot();
  return true;
}

std::shared_ptr<const octomap::OcTree> MapBuilder::snapshot() const {
  snapshot_wanted_.store(true, std::memory_order_relaxed);
  return std::atomic_load(&snapshot_);
}

}  // namespace auv::mapping
