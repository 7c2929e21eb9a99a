#include "auv/mapping/prior_registration.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <tuple>
#include <unordered_map>

namespace auv::mapping::detail {

Registration::Registration(std::vector<Eigen::Vector3d> points, std::vector<Eigen::Vector3d> seabed,
                           double resolution)
    : points_(std::move(points)), seabed_(std::move(seabed)), resolution_(resolution) {
  centre_.setZero();
  for (const auto& p : points_) centre_ += p.head<2>();
  centre_ /= static_cast<double>(points_.size());
  double sum = 0.0;
  for (const auto& p : points_) {
    const double r2 = (p.head<2>() - centre_).squaredNorm();
    sum += r2;
    max_radius_ = std::max(max_radius_, std::sqrt(r2));
  }
  rms_radius_ = std::max(resolution_, std::sqrt(sum / static_cast<double>(points_.size())));
}

bool Registration::buildGrid(const std::vector<Cell>& occupied, double search_radius,
                             double z_margin) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const auto& p : points_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (const auto& p : seabed_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double reach = max_radius_ + search_radius + 4.0 * resolution_ + kMinShiftM;
  lo.head<2>() = centre_.array() - reach;
  hi.head<2>() = centre_.array() + reach;
  lo.z() -= z_margin + 3.0 * resolution_;
  hi.z() += z_margin + 3.0 * resolution_;
  if (!grid_.reset(cellOf(lo, resolution_), cellOf(hi, resolution_))) return false;
  for (const Cell& c : occupied) {
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const std::ptrdiff_t i = grid_.linear(c + Cell(dx, dy, dz));
          if (i < 0) continue;
          const bool self = dx == 0 && dy == 0 && dz == 0;
          grid_.values[i] = std::max<uint8_t>(grid_.values[i], self ? 2 : 1);
        }
      }
    }
  }
  return true;
}

Eigen::Vector3d Registration::apply(const Placement& p, const Eigen::Vector3d& point) const {
  const Eigen::Vector2d d = point.head<2>() - centre_;
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  return Eigen::Vector3d(c * d.x() - s * d.y() + centre_.x() + p.tx,
                         s * d.x() + c * d.y() + centre_.y() + p.ty, point.z() + p.tz);
}

Eigen::Isometry3d Registration::isometry(const Placement& p) const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d c(centre_.x(), centre_.y(), 0.0);
  t.translation() = c + Eigen::Vector3d(p.tx, p.ty, p.tz) - t.linear() * c;
  return t;
}

double Registration::distance(const Placement& a, const Placement& b) const {
  return std::hypot(std::hypot(a.tx - b.tx, a.ty - b.ty), rms_radius_ * (a.yaw - b.yaw));
}

std::vector<Placement> Registration::coarseSearch(double search_radius, double search_yaw) const {
  const int n_t = static_cast<int>(std::ceil(search_radius / resolution_ - 1e-9));
  const double yaw_step = std::clamp(resolution_ / rms_radius_, 0.5 * kDegree, 2.0 * kDegree);
  const int n_yaw = search_yaw > 0.0 ? static_cast<int>(std::ceil(search_yaw / yaw_step)) : 0;
  std::vector<std::pair<int, int>> offsets;
  for (int i = -n_t; i <= n_t; ++i) {
    for (int j = -n_t; j <= n_t; ++j) {
      if (i * i + j * j <= n_t * n_t) offsets.emplace_back(i, j);
    }
  }
  struct Scored {
    double score;
    Placement placement;
  };
  std::vector<Scored> scored;
  scored.reserve(offsets.size() * (2 * n_yaw + 1));
  std::vector<std::ptrdiff_t> base(points_.size());
  for (int k = -n_yaw; k <= n_yaw; ++k) {
    Placement rotated;
    rotated.yaw = n_yaw > 0 ? search_yaw * k / n_yaw : 0.0;
    for (std::size_t n = 0; n < points_.size(); ++n) {
      base[n] = grid_.linear(cellOf(apply(rotated, points_[n]), resolution_));
    }
    for (const auto& [i, j] : offsets) {
      const std::ptrdiff_t shift = std::ptrdiff_t(j) * grid_.size.x() + i;
      long sum = 0;
      for (std::ptrdiff_t b : base) sum += grid_.values[b + shift];  // inside: see buildGrid
      Placement p = rotated;
      p.tx = i * resolution_;
      p.ty = j * resolution_;
      scored.push_back({sum / (2.0 * points_.size()), p});
    }
  }
  std::sort(scored.begin(), scored.end(),
            [](const Scored& a, const Scored& b) { return a.score > b.score; });
  std::vector<Placement> peaks;
  for (const Scored& s : scored) {
    const bool distinct = std::all_of(peaks.begin(), peaks.end(), [&](const Placement& p) {
      return distance(p, s.placement) > kMinShiftM;
    });
    if (distinct) peaks.push_back(s.placement);
    if (static_cast<int>(peaks.size()) == kCandidates) break;
  }
  return peaks;
}

bool Registration::nearest(const Eigen::Vector3d& q, int reach, Eigen::Vector3d* centre) const {
  const Cell c = cellOf(q, resolution_);
  double best = 1e300;
  for (int dz = -reach; dz <= reach; ++dz) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const Cell n = c + Cell(dx, dy, dz);
        if (grid_.at(n) != 2) continue;
        const Eigen::Vector3d m = centreOf(n, resolution_);
        const double d = (m - q).squaredNorm();
        if (d < best) {
          best = d;
          *centre = m;
        }
      }
    }
  }
  return best < 1e300;
}

double Registration::inlierFraction(const Placement& p, double* rms) const {
  std::size_t inliers = 0;
  double sum = 0.0;
  for (const auto& point : points_) {
    const Eigen::Vector3d q = apply(p, point);
    Eigen::Vector3d m;
    if (!nearest(q, 1, &m)) continue;
    const double d2 = (m - q).squaredNorm();
    if (d2 > resolution_ * resolution_) continue;
    ++inliers;
    sum += d2;
  }
  if (rms) *rms = inliers ? std::sqrt(sum / inliers) : 0.0;
  return static_cast<double>(inliers) / static_cast<double>(points_.size());
}

Fit Registration::refine(Placement p, bool refine_z) const {
  const double huber = 0.5 * resolution_;
  for (int iteration = 0; iteration < 40; ++iteration) {
    const int reach = iteration < 10 ? 2 : 1;
    const double cap = reach * resolution_;
    Eigen::Vector2d q_mean = Eigen::Vector2d::Zero(), m_mean = Eigen::Vector2d::Zero();
    std::vector<std::tuple<Eigen::Vector2d, Eigen::Vector2d, double>> pairs;
    pairs.reserve(points_.size());
    double weight_sum = 0.0;
    for (const auto& point : points_) {
      const Eigen::Vector3d q = apply(p, point);
      Eigen::Vector3d m;
      if (!nearest(q, reach, &m)) continue;
      const double r = (m - q).norm();
      if (r > cap) continue;
      const double w = r <= huber ? 1.0 : huber / r;
      pairs.emplace_back(q.head<2>(), m.head<2>(), w);
      q_mean += w * q.head<2>();
      m_mean += w * m.head<2>();
      weight_sum += w;
    }
    if (pairs.size() < 10) break;
    q_mean /= weight_sum;
    m_mean /= weight_sum;
    double sxx = 0.0, sxy = 0.0;  // weighted 2-D Procrustes: the rotation's cos and sin
    for (const auto& [q, m, w] : pairs) {
      const Eigen::Vector2d a = q - q_mean, b = m - m_mean;
      sxx += w * (a.x() * b.x() + a.y() * b.y());
      sxy += w * (a.x() * b.y() - a.y() * b.x());
    }
    const double d_yaw = std::atan2(sxy, sxx);
    const Eigen::Rotation2Dd rotation(d_yaw);
    const Eigen::Vector2d d_t = m_mean - rotation * q_mean;
    // Compose: new q = R(d_yaw) q + d_t, with q = R(yaw)(x - c) + c + t.
    const Eigen::Vector2d c_plus_t = centre_ + Eigen::Vector2d(p.tx, p.ty);
    const Eigen::Vector2d moved = rotation * c_plus_t + d_t - centre_;
    const double step = (moved - Eigen::Vector2d(p.tx, p.ty)).norm() + rms_radius_ * d_yaw;
    p.tx = moved.x();
    p.ty = moved.y();
    p.yaw += d_yaw;
    if (refine_z) p.tz += depthCorrection(p, huber);
    if (std::abs(step) < 1e-5 && iteration >= 10) break;
  }
  Fit fit;
  fit.placement = p;
  fit.inlier_fraction = inlierFraction(p, &fit.rms);
  return fit;
}

double Registration::constraint(const Fit& fit) const {
  if (fit.inlier_fraction <= 0.0) return 0.0;
  double smallest = 1.0;
  auto loss = [&](Placement p) {
    smallest = std::min(smallest, 1.0 - inlierFraction(p) / fit.inlier_fraction);
  };
  for (int k = 0; k < 24; ++k) {
    Placement p = fit.placement;
    p.tx += kMinShiftM * std::cos(k * 15.0 * kDegree);
    p.ty += kMinShiftM * std::sin(k * 15.0 * kDegree);
    loss(p);
  }
  for (double sign : {-1.0, 1.0}) {
    Placement p = fit.placement;
    p.yaw += sign * kMinShiftM / rms_radius_;
    loss(p);
  }
  return std::max(0.0, smallest);
}

double Registration::depthCorrection(const Placement& p, double huber) const {
  double sum = 0.0, weights = 0.0;
  for (const auto& point : seabed_) {
    const Eigen::Vector3d q = apply(p, point);
    Eigen::Vector3d m;
    if (!nearest(q, 1, &m) || (m - q).norm() > resolution_) continue;
    const double r = m.z() - q.z();
    const double w = std::abs(r) <= huber ? 1.0 : huber / std::abs(r);
    sum += w * r;
    weights += w;
  }
  return weights > 0.0 ? sum / weights : 0.0;
}

/// Splits the submap's mean points into steep-surface ("structure") and near-horizontal
/// (seabed) returns by the normal of each cell's neighbourhood (cells within two): planar with
/// a normal within 30 degrees of vertical is seabed. Sparse or non-planar neighbourhoods count
/// as structure.
void classify(const std::vector<Cell>& cells, const std::vector<Eigen::Vector3d>& means,
              std::vector<Eigen::Vector3d>* structure, std::vector<Eigen::Vector3d>* seabed) {
  Cell lo = Cell::Constant(1 << 30), hi = -lo;
  for (const Cell& c : cells) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  DenseGrid<uint32_t> grid;  // 1 + index of the cell's mean, 0 = empty
  const bool dense = grid.reset(lo.array() - 2, hi.array() + 2);
  std::unordered_map<uint64_t, uint32_t> sparse;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (dense) {
      grid.values[grid.linear(cells[i])] = static_cast<uint32_t>(i + 1);
    } else {
      sparse[pack(cells[i])] = static_cast<uint32_t>(i + 1);
    }
  }
  const auto lookup = [&](const Cell& c) -> uint32_t {
    if (dense) return grid.at(c);
    const auto it = sparse.find(pack(c));
    return it == sparse.end() ? 0 : it->second;
  };
  const double cos_30 = std::cos(30.0 * kDegree);
  std::vector<Eigen::Vector3d> neighbours;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    neighbours.clear();
    for (int dz = -2; dz <= 2; ++dz) {
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          if (const uint32_t n = lookup(cells[i] + Cell(dx, dy, dz))) {
            neighbours.push_back(means[n - 1]);
          }
        }
      }
    }
    bool horizontal = false;
    if (neighbours.size() >= 6) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const auto& n : neighbours) mean += n;
      mean /= static_cast<double>(neighbours.size());
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      for (const auto& n : neighbours) covariance += (n - mean) * (n - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
      const Eigen::Vector3d values = solver.eigenvalues();  // ascending
      const bool planar = values(0) < 0.25 * values(1);
      // A seabed patch spreads both ways; one line of cells (a horizontal profiling sonar's trace
      // along a wall, all at one depth) also fits a level plane but is a wall.
      const bool spread = values(1) > 0.1 * values(2);
      horizontal = planar && spread && std::abs(solver.eigenvectors().col(0).z()) >= cos_30;
    }
    (horizontal ? seabed : structure)->push_back(means[i]);
  }
}

/// Extent of points along their main horizontal direction (5th to 95th percentile).
double mainExtent(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p.head<2>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  for (const auto& p : points) {
    covariance += (p.head<2>() - mean) * (p.head<2>() - mean).transpose();
  }
  const Eigen::Vector2d axis =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance).eigenvectors().col(1);
  std::vector<double> along;
  along.reserve(points.size());
  for (const auto& p : points) along.push_back(axis.dot(p.head<2>() - mean));
  const auto at = [&](double q) {
    auto it = along.begin() + static_cast<std::ptrdiff_t>(q * (along.size() - 1));
    std::nth_element(along.begin(), it, along.end());
    return *it;
  };
  const double low = at(0.05);
  return at(0.95) - low;
}

/// Every n-th point, at most `limit` (arrival order: thinning keeps the spread).
std::vector<Eigen::Vector3d> thin(const std::vector<Eigen::Vector3d>& points, std::size_t limit) {
  if (points.size() <= limit) return points;
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(limit);
  const double stride = static_cast<double>(points.size()) / static_cast<double>(limit);
  for (std::size_t k = 0; k < limit; ++k) kept.push_back(points[std::size_t(k * stride)]);
  return kept;
}

}  // namespace auv::mapping::detail
