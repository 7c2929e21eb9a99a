#pragma once
// The registration behind PriorMapAlignment (internal to it): one attempt's returns against a
// dense grid of the prior's occupied cells, with the coarse search, the ICP and the tests the
// alignment is judged by. Cells are integer indices floor(p / resolution) in any frame: the
// prior's OctoMap keys minus the key of 0.

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace auv::mapping::detail {

inline constexpr double kDegree = M_PI / 180.0;
inline constexpr int kCandidates = 5;      // coarse peaks refined by ICP
inline constexpr double kMinShiftM = 2.0;  // "distinct" and the ridge test's shift
// Dense grids beyond this many bytes are refused (the registration's: the attempt fails; the
// classification's: a hash table instead).
inline constexpr std::size_t kMaxGridBytes = std::size_t{1} << 26;

using Cell = Eigen::Vector3i;

inline uint64_t pack(const Cell& c) {
  constexpr int64_t kOffset = 1 << 20;  // 21 bits per axis: +-1 M cells
  return (uint64_t(c.x() + kOffset) << 42) | (uint64_t(c.y() + kOffset) << 21) |
         uint64_t(c.z() + kOffset);
}

inline Cell cellOf(const Eigen::Vector3d& p, double resolution) {
  return Cell(static_cast<int>(std::floor(p.x() / resolution)),
              static_cast<int>(std::floor(p.y() / resolution)),
              static_cast<int>(std::floor(p.z() / resolution)));
}

inline Eigen::Vector3d centreOf(const Cell& c, double resolution) {
  return (c.cast<double>().array() + 0.5).matrix() * resolution;
}

/// A dense box of cells (bounds-checked lookups: 0 / default outside).
template <class T>
struct DenseGrid {
  Cell low = Cell::Zero();
  Cell size = Cell::Zero();
  std::vector<T> values;

  bool reset(const Cell& lo, const Cell& hi) {
    low = lo;
    size = (hi - lo).array() + 1;
    const std::size_t cells = std::size_t(size.x()) * size.y() * size.z();
    if (cells * sizeof(T) > kMaxGridBytes) return false;
    values.assign(cells, T{});
    return true;
  }
  std::ptrdiff_t linear(const Cell& c) const {
    const Cell d = c - low;
    if ((d.array() < 0).any() || (d.array() >= size.array()).any()) return -1;
    return (std::ptrdiff_t(d.z()) * size.y() + d.y()) * size.x() + d.x();
  }
  T at(const Cell& c) const {
    const std::ptrdiff_t i = linear(c);
    return i < 0 ? T{} : values[i];
  }
};

/// A placement of the submap in the prior's frame: rotation `yaw` about the submap's
/// horizontal centre, then translation (tx, ty, tz).
struct Placement {
  double tx = 0.0, ty = 0.0, yaw = 0.0, tz = 0.0;
};

struct Fit {
  Placement placement;
  double inlier_fraction = 0.0;
  double rms = 0.0;
};

/// One attempt's registration problem: thinned structure returns against a dense grid of the
/// prior's occupied cells (2) and their neighbours (1) around them.
class Registration {
 public:
  Registration(std::vector<Eigen::Vector3d> points, std::vector<Eigen::Vector3d> seabed,
               double resolution);

  /// The grid around every placement the search and ICP can reach; false if too large.
  bool buildGrid(const std::vector<Cell>& occupied, double search_radius, double z_margin);

  double rmsRadius() const { return rms_radius_; }
  std::size_t size() const { return points_.size(); }

  Eigen::Vector3d apply(const Placement& p, const Eigen::Vector3d& point) const;

  /// prior_T_navigation of a placement.
  Eigen::Isometry3d isometry(const Placement& p) const;

  /// Horizontal distance between placements, a yaw difference counted as its arc at the
  /// submap's RMS radius.
  double distance(const Placement& a, const Placement& b) const;

  /// The best distinct placements of a grid search over offset (whole cells) and yaw, scored
  /// by the points in (1) or next to (1/2) an occupied prior cell. Best first.
  std::vector<Placement> coarseSearch(double search_radius, double search_yaw) const;

  /// The nearest occupied prior cell centre within `reach` cells of q (per axis).
  bool nearest(const Eigen::Vector3d& q, int reach, Eigen::Vector3d* centre) const;

  /// Fraction of points within one cell size of an occupied prior cell centre, and their RMS.
  double inlierFraction(const Placement& p, double* rms = nullptr) const;

  /// Robust point-to-point ICP in x, y, yaw (and z from seabed returns if asked) against the
  /// occupied cell centres: Huber weights, correspondences trimmed at two then one cell.
  Fit refine(Placement p, bool refine_z) const;

  /// Smallest relative loss of inlier fraction over shifts of kMinShiftM in 24 horizontal
  /// directions and turns of the same arc: near 0 when a direction is unconstrained.
  double constraint(const Fit& fit) const;

 private:
  /// Huber-weighted mean depth residual of the seabed returns to their nearest occupied cells.
  double depthCorrection(const Placement& p, double huber) const;

  std::vector<Eigen::Vector3d> points_;
  std::vector<Eigen::Vector3d> seabed_;
  double resolution_;
  Eigen::Vector2d centre_;
  double rms_radius_ = 1.0;
  double max_radius_ = 0.0;
  DenseGrid<uint8_t> grid_;
};

/// Splits the submap's mean points into steep-surface ("structure") and near-horizontal
/// (seabed) returns by the normal of each cell's neighbourhood (cells within two): planar with
/// a normal within 30 degrees of vertical is seabed. Sparse or non-planar neighbourhoods count
/// as structure.
void classify(const std::vector<Cell>& cells, const std::vector<Eigen::Vector3d>& means,
              std::vector<Eigen::Vector3d>* structure, std::vector<Eigen::Vector3d>* seabed);

/// Extent of points along their main horizontal direction (5th to 95th percentile).
double mainExtent(const std::vector<Eigen::Vector3d>& points);

/// Every n-th point, at most `limit` (arrival order: thinning keeps the spread).
std::vector<Eigen::Vector3d> thin(const std::vector<Eigen::Vector3d>& points, std::size_t limit);

}  // namespace auv::mapping::detail
