#include "oracle.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <string>

#include <octomap/OcTree.h>

namespace auv::planning::bench {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
/// m, distance reported where the grid holds no occupied cell at all.
constexpr double kFarAway = 1e4;
/// Trilinear interpolation of a 1-Lipschitz grid function is at most √3-Lipschitz: a segment
/// can advance (distance - clearance) / √3 without missing a violation (sphere tracing).
const double kLipschitz = std::sqrt(3.0);
/// Parent of the nodes connected straight to the start point.
constexpr std::int32_t kStartParent = -2;
constexpr std::int32_t kNoParent = -1;

/// Felzenszwalb-Huttenlocher 1-D squared distance transform of `line` in place (finite values
/// are sources with that squared distance, infinite ones empty cells).
void distanceTransform1d(std::vector<double>& line, std::vector<int>& vertices,
                         std::vector<double>& bounds, std::vector<double>& out) {
  const int n = static_cast<int>(line.size());
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (!std::isfinite(line[q])) continue;
    if (k < 0) {
      k = 0;
      vertices[0] = q;
      bounds[0] = -kInfinity;
      bounds[1] = kInfinity;
      continue;
    }
    // Drop the parabolas the new one hides; bounds[0] = -inf stops the loop at the first.
    double s = 0.0;
    while (true) {
      const int p = vertices[k];
      s = ((line[q] + double(q) * q) - (line[p] + double(p) * p)) / (2.0 * q - 2.0 * p);
      if (s > bounds[k]) break;
      --k;
    }
    ++k;
    vertices[k] = q;
    bounds[k] = s;
    bounds[k + 1] = kInfinity;
  }
  if (k < 0) return;  // no source on this line
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (bounds[k + 1] < q) ++k;
    const double offset = q - vertices[k];
    out[q] = offset * offset + line[vertices[k]];
  }
  std::copy(out.begin(), out.end(), line.begin());
}

}  // namespace

void OracleOptions::check() const {
  if (!(clearance >= 0.0) || !std::isfinite(clearance)) {
    throw OracleError("oracle: clearance must be >= 0 m");
  }
  if (!(grid > 0.0) || !std::isfinite(grid)) throw OracleError("oracle: grid must be > 0 m");
  if (fixed_depth && !std::isfinite(*fixed_depth)) {
    throw OracleError("oracle: fixed_depth must be finite");
  }
  if (!std::isfinite(min_depth)) throw OracleError("oracle: min_depth must be finite");
  if (max_depth && !(*max_depth > min_depth && std::isfinite(*max_depth))) {
    throw OracleError("oracle: max_depth must be finite and > min_depth");
  }
  if (!(padding >= 0.0) || !std::isfinite(padding)) {
    throw OracleError("oracle: padding must be >= 0 m");
  }
}

double polylineLength(const std::vector<Eigen::Vector3d>& points) {
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

ShortestPathOracle::ShortestPathOracle(const octomap::OcTree& map, const OracleOptions& options)
    : options_(options) {
  options_.check();
  if (map.size() == 0) throw OracleError("oracle: the map is empty");
  double x0, y0, z0, x1, y1, z1;
  // calcMinMax() is not const; the map's bounds do not change here.
  const_cast<octomap::OcTree&>(map).getMetricMin(x0, y0, z0);
  const_cast<octomap::OcTree&>(map).getMetricMax(x1, y1, z1);
  const double g = options_.grid;
  Eigen::Vector3d low(x0, y0, z0), high(x1, y1, z1);
  low.array() -= options_.padding;
  high.array() += options_.padding;
  z0 = low.z();
  z1 = high.z();
  if (options_.fixed_depth) {
    const double depth = *options_.fixed_depth;
    if (depth < z0 || depth > z1 || depth < options_.min_depth ||
        (options_.max_depth && depth > *options_.max_depth)) {
      throw OracleError("oracle: fixed depth " + std::to_string(depth) +
                        " m lies outside the map's depths or the depth band");
    }
    // Only obstacles within the clearance of the plane matter: a slab around it is enough.
    low.z() = std::max(z0, depth - options_.clearance - 2.0 * g);
    high.z() = std::min(z1, depth + options_.clearance + 2.0 * g);
  }
  for (int axis = 0; axis < 3; ++axis) {
    // Cells aligned to multiples of the grid step line up with the map's voxels.
    origin_[axis] = std::floor(low[axis] / g + 1e-9) * g;
    const double cells = std::ceil((high[axis] - origin_[axis]) / g - 1e-9);
    if (cells < 1.0 || cells > 1e5) throw OracleError("oracle: the grid is empty or too large");
    size_[axis] = static_cast<int>(cells);
  }
  const double total = double(size_[0]) * size_[1] * size_[2];
  if (total > 4e8) {
    throw OracleError("oracle: " + std::to_string(total) +
                      " grid cells: use a coarser grid or a fixed depth");
  }
  for (int axis = 0; axis < 3; ++axis) {
    min_corner_[axis] = origin_[axis] + 0.5 * g;
    max_corner_[axis] = origin_[axis] + (size_[axis] - 0.5) * g;
  }
  if (options_.fixed_depth) {
    min_corner_.z() = max_corner_.z() = *options_.fixed_depth;
    search_layers_ = 1;
  } else {
    min_corner_.z() = std::max(min_corner_.z(), options_.min_depth);
    if (options_.max_depth) max_corner_.z() = std::min(max_corner_.z(), *options_.max_depth);
    search_layers_ = size_[2];
  }
  if (double(size_[0]) * size_[1] * search_layers_ >= double(std::numeric_limits<int32_t>::max())) {
    throw OracleError("oracle: too many search nodes: use a coarser grid");
  }
  rasterise(map);
  distanceTransform();
}

void ShortestPathOracle::rasterise(const octomap::OcTree& map) {
  distance_.assign(static_cast<std::size_t>(size_[0]) * size_[1] * size_[2], kInfinity);
  const double g = options_.grid;
  for (auto it = map.begin_leafs(), end = map.end_leafs(); it != end; ++it) {
    if (!map.isNodeOccupied(*it)) continue;
    const double half = 0.5 * it.getSize();
    const Eigen::Vector3d centre(it.getX(), it.getY(), it.getZ());
    int lo[3], hi[3];
    bool outside = false;
    for (int axis = 0; axis < 3; ++axis) {
      // Every cell the voxel's cube overlaps (a hair inside, so touching faces do not count).
      lo[axis] = std::max(
          0, static_cast<int>(std::floor((centre[axis] - half - origin_[axis]) / g + 1e-6)));
      hi[axis] = std::min(
          size_[axis] - 1,
          static_cast<int>(std::ceil((centre[axis] + half - origin_[axis]) / g - 1e-6)) - 1);
      outside |= lo[axis] > hi[axis];
    }
    if (outside) continue;
    for (int k = lo[2]; k <= hi[2]; ++k) {
      for (int j = lo[1]; j <= hi[1]; ++j) {
        for (int i = lo[0]; i <= hi[0]; ++i) distance_[cellIndex(i, j, k)] = 0.0f;
      }
    }
  }
}

void ShortestPathOracle::distanceTransform() {
  const int longest = std::max({size_[0], size_[1], size_[2]});
  std::vector<int> vertices(longest);
  std::vector<double> bounds(longest + 1), out(longest), line;
  const Index strides[3] = {1, size_[0], Index(size_[0]) * size_[1]};
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    line.assign(size_[axis], 0.0);
    out.assign(size_[axis], kInfinity);
    for (int u = 0; u < size_[a]; ++u) {
      for (int v = 0; v < size_[b]; ++v) {
        const Index base = u * strides[a] + v * strides[b];
        for (int q = 0; q < size_[axis]; ++q) line[q] = distance_[base + q * strides[axis]];
        distanceTransform1d(line, vertices, bounds, out);
        for (int q = 0; q < size_[axis]; ++q) {
          distance_[base + q * strides[axis]] = static_cast<float>(line[q]);
        }
      }
    }
  }
  for (float& value : distance_) {
    value = std::isfinite(value) ? std::sqrt(value) * static_cast<float>(options_.grid)
                                 : static_cast<float>(kFarAway);
  }
}

double ShortestPathOracle::distance(const Eigen::Vector3d& position) const {
  int cell[3];
  double fraction[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double u = (position[axis] - origin_[axis]) / options_.grid - 0.5;
    if (u < -1e-9 || u > size_[axis] - 1 + 1e-9) return 0.0;
    cell[axis] = std::clamp(static_cast<int>(std::floor(u)), 0, std::max(0, size_[axis] - 2));
    fraction[axis] = size_[axis] == 1 ? 0.0 : std::clamp(u - cell[axis], 0.0, 1.0);
  }
  double value = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    double weight = 1.0;
    int index[3];
    for (int axis = 0; axis < 3; ++axis) {
      const bool upper = (corner >> axis) & 1;
      weight *= upper ? fraction[axis] : 1.0 - fraction[axis];
      index[axis] = std::min(cell[axis] + (upper ? 1 : 0), size_[axis] - 1);
    }
    if (weight > 0.0) value += weight * distance_[cellIndex(index[0], index[1], index[2])];
  }
  return value;
}

Eigen::Vector3d ShortestPathOracle::distanceGradient(const Eigen::Vector3d& position) const {
  const double h = 0.5 * options_.grid;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < (options_.fixed_depth ? 2 : 3); ++axis) {
    const Eigen::Vector3d offset = h * Eigen::Vector3d::Unit(axis);
    gradient[axis] = distance(position + offset) - distance(position - offset);
  }
  const double norm = gradient.norm();
  return norm > 0.0 ? Eigen::Vector3d(gradient / norm) : Eigen::Vector3d::Zero();
}

double ShortestPathOracle::bottleneckClearance(const Eigen::Vector3d& start,
                                               const Eigen::Vector3d& goal, double tolerance) {
  if (!(tolerance > 0.0)) throw OracleError("oracle: bottleneck tolerance must be > 0 m");
  const double upper = options_.clearance;  // the fixed-depth slab was sized for it
  auto joined = [&](double clearance) {
    options_.clearance = clearance;
    try {
      return shortestPath(start, goal).found;
    } catch (const OracleError&) {
      return false;  // start or goal itself closer than the clearance
    }
  };
  double low = 0.0, high = upper;
  if (joined(upper)) {
    low = upper;
  } else if (!joined(0.0)) {
    high = 0.0;
  } else {
    while (high - low > tolerance) {
      const double middle = 0.5 * (low + high);
      (joined(middle) ? low : high) = middle;
    }
  }
  options_.clearance = upper;
  return low;
}

bool ShortestPathOracle::isFree(const Eigen::Vector3d& position) const {
  constexpr double kSlack = 1e-9;
  for (int axis = 0; axis < 3; ++axis) {
    if (position[axis] < min_corner_[axis] - kSlack ||
        position[axis] > max_corner_[axis] + kSlack) {
      return false;
    }
  }
  return distance(position) >= options_.clearance;
}

bool ShortestPathOracle::lineOfSight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  const double length = (b - a).norm();
  const Eigen::Vector3d direction =
      length > 0.0 ? Eigen::Vector3d((b - a) / length) : Eigen::Vector3d::Zero();
  // Below this step a grazing segment would crawl; it can miss a violation by ~grid/10 only.
  const double min_step = options_.grid / 16.0;
  for (double t = 0.0;;) {
    const Eigen::Vector3d p = a + t * direction;
    if (!isFree(p)) return false;
    if (t >= length) return true;
    const double step = std::max(min_step, (distance(p) - options_.clearance) / kLipschitz);
    t = std::min(length, t + step);
  }
}

ShortestPathOracle::Index ShortestPathOracle::nodeCount() const {
  return Index(size_[0]) * size_[1] * search_layers_;
}

Eigen::Vector3d ShortestPathOracle::nodePosition(Index node) const {
  const int i = static_cast<int>(node % size_[0]);
  const int j = static_cast<int>((node / size_[0]) % size_[1]);
  const int k = static_cast<int>(node / (Index(size_[0]) * size_[1]));
  const double g = options_.grid;
  return {origin_.x() + (i + 0.5) * g, origin_.y() + (j + 0.5) * g,
          options_.fixed_depth ? *options_.fixed_depth : origin_.z() + (k + 0.5) * g};
}

std::optional<ShortestPathOracle::Index> ShortestPathOracle::nodeAt(
    const Eigen::Vector3d& position) const {
  int cell[3] = {0, 0, 0};
  for (int axis = 0; axis < (options_.fixed_depth ? 2 : 3); ++axis) {
    const double u = std::floor((position[axis] - origin_[axis]) / options_.grid);
    if (u < 0 || u >= size_[axis]) return std::nullopt;
    cell[axis] = static_cast<int>(u);
  }
  return cell[0] + Index(size_[0]) * (cell[1] + Index(size_[1]) * cell[2]);
}

OraclePath ShortestPathOracle::shortestPath(const Eigen::Vector3d& start_in,
                                            const Eigen::Vector3d& goal_in) const {
  Eigen::Vector3d start = start_in, goal = goal_in;
  if (options_.fixed_depth) start.z() = goal.z() = *options_.fixed_depth;
  auto describe = [](const Eigen::Vector3d& p) {
    return "(" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
           std::to_string(p.z()) + ")";
  };
  if (!isFree(start)) {
    throw OracleError("oracle: start " + describe(start) + " is outside the map or only " +
                      std::to_string(distance(start)) + " m from it (clearance " +
                      std::to_string(options_.clearance) + " m)");
  }
  if (!isFree(goal)) {
    throw OracleError("oracle: goal " + describe(goal) + " is outside the map or only " +
                      std::to_string(distance(goal)) + " m from it (clearance " +
                      std::to_string(options_.clearance) + " m)");
  }
  OraclePath result;
  if (lineOfSight(start, goal)) {
    result.found = true;
    result.points = {start, goal};
    result.length = (goal - start).norm();
    return result;
  }

  // Lazy Theta* (Nash, Koenig & Tovey 2010): a node's parent may be any earlier node in sight;
  // the sight line is checked when the node is expanded, not when it is reached.
  const Index count = nodeCount();
  std::vector<float> cost(count, kInfinity);
  std::vector<std::int32_t> parent(count, kNoParent);
  std::vector<std::uint8_t> closed(count, 0);
  std::vector<std::int8_t> free_cache(count, -1);
  auto nodeFree = [&](Index node) {
    if (free_cache[node] < 0) free_cache[node] = isFree(nodePosition(node)) ? 1 : 0;
    return free_cache[node] == 1;
  };
  auto parentPosition = [&](std::int32_t p) { return p == kStartParent ? start : nodePosition(p); };
  auto parentCost = [&](std::int32_t p) { return p == kStartParent ? 0.0 : double(cost[p]); };
  using Entry = std::pair<double, Index>;  // f = cost + straight distance to the goal
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  auto push = [&](Index node, double g_cost, std::int32_t from) {
    cost[node] = static_cast<float>(g_cost);
    parent[node] = from;
    open.emplace(g_cost + (nodePosition(node) - goal).norm(), node);
  };

  const int dims = options_.fixed_depth ? 2 : 3;
  const int nx = size_[0], ny = size_[1], nz = search_layers_;
  auto forEachNeighbour = [&](Index node, auto&& visit) {
    const int i = static_cast<int>(node % nx);
    const int j = static_cast<int>((node / nx) % ny);
    const int k = static_cast<int>(node / (Index(nx) * ny));
    for (int dz = dims == 3 ? -1 : 0; dz <= (dims == 3 ? 1 : 0); ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const int ni = i + dx, nj = j + dy, nk = k + dz;
          if (ni < 0 || nj < 0 || nk < 0 || ni >= nx || nj >= ny || nk >= nz) continue;
          visit(ni + Index(nx) * (nj + Index(ny) * nk));
        }
      }
    }
  };

  // Seeds: free nodes around the start it can see; goals: nodes around the goal that see it.
  const double reach = 2.0 * options_.grid;
  const auto start_node = nodeAt(start);
  const auto goal_node = nodeAt(goal);
  if (!start_node || !goal_node) throw OracleError("oracle: start or goal outside the grid");
  auto nearbyNodes = [&](Index centre, const Eigen::Vector3d& point, auto&& visit) {
    const int r = 2;
    const int i = static_cast<int>(centre % nx), j = static_cast<int>((centre / nx) % ny);
    const int k = static_cast<int>(centre / (Index(nx) * ny));
    for (int dz = dims == 3 ? -r : 0; dz <= (dims == 3 ? r : 0); ++dz) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
          const int ni = i + dx, nj = j + dy, nk = k + dz;
          if (ni < 0 || nj < 0 || nk < 0 || ni >= nx || nj >= ny || nk >= nz) continue;
          const Index node = ni + Index(nx) * (nj + Index(ny) * nk);
          if ((nodePosition(node) - point).norm() <= reach && nodeFree(node)) visit(node);
        }
      }
    }
  };
  nearbyNodes(*start_node, start, [&](Index node) {
    if (lineOfSight(start, nodePosition(node)))
      push(node, (nodePosition(node) - start).norm(), kStartParent);
  });
  std::vector<std::uint8_t> is_goal(count, 0);
  nearbyNodes(*goal_node, goal, [&](Index node) {
    if (lineOfSight(nodePosition(node), goal)) is_goal[node] = 1;
  });

  Index reached = -1;
  while (!open.empty()) {
    const auto [f, node] = open.top();
    open.pop();
    if (closed[node]) continue;
    const Eigen::Vector3d position = nodePosition(node);
    if (f > cost[node] + (position - goal).norm() + 1e-6) continue;  // superseded entry
    // Lazy check: without sight to the parent, take the best closed neighbour instead.
    if (!lineOfSight(parentPosition(parent[node]), position)) {
      double best = kInfinity;
      std::int32_t best_parent = kNoParent;
      forEachNeighbour(node, [&](Index neighbour) {
        if (!closed[neighbour]) return;
        const double candidate = cost[neighbour] + (nodePosition(neighbour) - position).norm();
        if (candidate < best) {
          best = candidate;
          best_parent = static_cast<std::int32_t>(neighbour);
        }
      });
      if (best_parent == kNoParent) continue;  // cannot happen: it was reached from one
      cost[node] = static_cast<float>(best);
      parent[node] = best_parent;
    }
    closed[node] = 1;
    ++result.expanded;
    if (is_goal[node]) {
      reached = node;
      break;
    }
    const std::int32_t from = parent[node];
    const Eigen::Vector3d from_position = parentPosition(from);
    const double from_cost = parentCost(from);
    forEachNeighbour(node, [&](Index neighbour) {
      if (closed[neighbour] || !nodeFree(neighbour)) return;
      // The grid edge must be passable too (it is the fallback when the sight line fails).
      if (!isFree(0.5 * (position + nodePosition(neighbour)))) return;
      const double candidate = from_cost + (nodePosition(neighbour) - from_position).norm();
      if (candidate < cost[neighbour]) push(neighbour, candidate, from);
    });
  }
  if (reached < 0) return result;

  std::vector<Eigen::Vector3d> corners{goal};
  for (std::int32_t node = static_cast<std::int32_t>(reached); node != kStartParent;
       node = parent[node]) {
    corners.push_back(nodePosition(node));
  }
  corners.push_back(start);
  std::reverse(corners.begin(), corners.end());
  // Shortcut: from each kept corner, jump to the farthest corner in sight.
  result.points = {start};
  for (std::size_t i = 0; i + 1 < corners.size();) {
    std::size_t j = corners.size() - 1;
    while (j > i + 1 && !lineOfSight(corners[i], corners[j])) --j;
    result.points.push_back(corners[j]);
    i = j;
  }
  result.points = tighten(std::move(result.points));
  result.found = true;
  result.length = polylineLength(result.points);
  return result;
}

std::vector<Eigen::Vector3d> ShortestPathOracle::tighten(
    std::vector<Eigen::Vector3d> points) const {
  // Corners of a grid search sit on cell centres, outside the clearance boundary: round a
  // curved obstacle that costs up to a few percent. Pull the polyline taut like a string:
  // subdivide, move every inner vertex towards the middle of its neighbours as far as both its
  // segments stay free; a few rounds, then drop the vertices that are not needed. (Dropping
  // them between rounds would undo the subdivision and lock corners in place.)
  constexpr int kRounds = 5, kSweeps = 40, kBisections = 10;
  for (int round = 0; round < kRounds && points.size() > 2; ++round) {
    std::vector<Eigen::Vector3d> finer{points.front()};
    for (std::size_t i = 1; i < points.size(); ++i) {
      // Sight lines are sampled: a half of a free segment is checked again before it counts.
      const Eigen::Vector3d middle = 0.5 * (points[i - 1] + points[i]);
      if ((points[i] - points[i - 1]).norm() > options_.grid && lineOfSight(finer.back(), middle) &&
          lineOfSight(middle, points[i])) {
        finer.push_back(middle);
      }
      finer.push_back(points[i]);
    }
    points = std::move(finer);
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      double moved = 0.0;
      for (std::size_t i = 1; i + 1 < points.size(); ++i) {
        const Eigen::Vector3d step = 0.5 * (points[i - 1] + points[i + 1]) - points[i];
        if (step.norm() < 1e-9) continue;
        auto passable = [&](const Eigen::Vector3d& q) {
          return lineOfSight(points[i - 1], q) && lineOfSight(q, points[i + 1]);
        };
        auto span = [&](const Eigen::Vector3d& q) {
          return (q - points[i - 1]).norm() + (points[i + 1] - q).norm();
        };
        // Along the pull, as far as the segments stay free.
        double low = 0.0, high = 1.0;
        if (passable(points[i] + step)) {
          low = 1.0;
        } else {
          for (int b = 0; b < kBisections; ++b) {
            const double middle = 0.5 * (low + high);
            (passable(points[i] + middle * step) ? low : high) = middle;
          }
        }
        Eigen::Vector3d best = points[i] + low * step;
        // A vertex next to one lying on the clearance boundary cannot be pulled in (the chord
        // would cut the boundary): pull it fully, then push it out along the distance gradient
        // just far enough; the pair then slides along the boundary.
        if (low < 1.0) {
          const Eigen::Vector3d target = points[i] + step;
          const Eigen::Vector3d out = distanceGradient(target);
          double inside = 0.0, outside = 2.0 * options_.grid;
          if (out.norm() > 0.0 && passable(target + outside * out)) {
            for (int b = 0; b < kBisections; ++b) {
              const double middle = 0.5 * (inside + outside);
              (passable(target + middle * out) ? outside : inside) = middle;
            }
            const Eigen::Vector3d pushed = target + outside * out;
            if (span(pushed) < span(best)) best = pushed;
          }
        }
        if (span(best) < span(points[i])) {
          moved += (best - points[i]).norm();
          points[i] = best;
        }
      }
      if (moved < 1e-5) break;
    }
  }
  std::vector<Eigen::Vector3d> kept{points.front()};
  for (std::size_t i = 0; i + 1 < points.size();) {
    std::size_t j = points.size() - 1;
    while (j > i + 1 && !lineOfSight(points[i], points[j])) --j;
    kept.push_back(points[j]);
    i = j;
  }
  points = std::move(kept);
  return points;
}

}  // namespace auv::planning::bench
