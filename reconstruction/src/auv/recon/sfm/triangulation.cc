#include "auv/recon/sfm/triangulation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace auv::recon::sfm {

std::optional<Eigen::Vector3d> triangulateDlt(const std::vector<PosedObservation>& observations) {
  if (observations.size() < 2) return std::nullopt;
  Eigen::MatrixXd a(2 * observations.size(), 4);
  for (size_t i = 0; i < observations.size(); ++i) {
    const Matrix34d& p = observations[i].pose_cw;
    const Eigen::Vector2d& x = observations[i].normalized;
    Eigen::RowVector4d r0 = x.x() * p.row(2) - p.row(0);
    Eigen::RowVector4d r1 = x.y() * p.row(2) - p.row(1);
    a.row(2 * i) = r0 / std::max(r0.norm(), 1e-12);
    a.row(2 * i + 1) = r1 / std::max(r1.norm(), 1e-12);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h(3)) < 1e-12 * h.head<3>().norm() || !h.allFinite()) return std::nullopt;
  return Eigen::Vector3d(h.head<3>() / h(3));
}

Eigen::Vector3d refineTriangulation(const std::vector<PosedObservation>& observations,
                                    const Eigen::Vector3d& start, int iterations) {
  Eigen::Vector3d x = start;
  for (int it = 0; it < iterations; ++it) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const auto& o : observations) {
      const Eigen::Vector3d p = o.pose_cw.leftCols<3>() * x + o.pose_cw.col(3);
      if (p.z() <= 1e-12) return x;  // behind a camera: leave it to the caller's checks
      const double iz = 1.0 / p.z();
      const Eigen::Vector2d r(p.x() * iz - o.normalized.x(), p.y() * iz - o.normalized.y());
      Eigen::Matrix<double, 2, 3> dp;
      dp << iz, 0, -p.x() * iz * iz, 0, iz, -p.y() * iz * iz;
      const Eigen::Matrix<double, 2, 3> j = dp * o.pose_cw.leftCols<3>();
      jtj += j.transpose() * j;
      jtr += j.transpose() * r;
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    x += step;
    if (step.norm() < 1e-12 * (1 + x.norm())) break;
  }
  return x;
}

double triangulationAngle(const Eigen::Vector3d& center_a, const Eigen::Vector3d& center_b,
                          const Eigen::Vector3d& point) {
  const Eigen::Vector3d ra = center_a - point, rb = center_b - point;
  const double na = ra.norm(), nb = rb.norm();
  if (na <= 0 || nb <= 0) return 0;
  return std::acos(std::clamp(ra.dot(rb) / (na * nb), -1.0, 1.0));
}

}  // namespace auv::recon::sfm
