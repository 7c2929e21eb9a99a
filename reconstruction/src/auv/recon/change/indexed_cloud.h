#pragma once
// A point cloud with its search tree, for the radius queries of the comparisons (Open3D's
// KDTreeFlann refers to the matrix it is given: both live here, with the points referenced).
#include <vector>

#include <open3d/geometry/KDTreeFlann.h>
#include <Eigen/Core>

namespace auv::recon::change {

inline Eigen::MatrixXd toMatrix(const std::vector<Eigen::Vector3d>& points) {
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = points[i];
  return matrix;
}

/// `points` must outlive the cloud.
class IndexedCloud {
 public:
  explicit IndexedCloud(const std::vector<Eigen::Vector3d>& points)
      : points_(points), matrix_(toMatrix(points)) {
    if (!points.empty()) tree_.SetMatrixData(matrix_);
  }
  /// Indices of the points within `radius` of `centre`.
  std::vector<int> within(const Eigen::Vector3d& centre, double radius) const {
    std::vector<int> indices;
    std::vector<double> distance2;
    if (!points_.empty()) tree_.SearchRadius(centre, radius, indices, distance2);
    return indices;
  }
  const Eigen::Vector3d& operator[](int i) const { return points_[static_cast<size_t>(i)]; }

 private:
  const std::vector<Eigen::Vector3d>& points_;
  Eigen::MatrixXd matrix_;
  open3d::geometry::KDTreeFlann tree_;
};

}  // namespace auv::recon::change
