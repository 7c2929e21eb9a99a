#pragma once
// Triangulation of points seen by posed cameras (paper section 3.4.2: new points are
// triangulated with angle and reprojection checks).

#include <optional>
#include <vector>

#include <Eigen/Core>

namespace auv::recon::sfm {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

/// One observation: the world -> camera pose [R | t] and the normalised image coordinates
/// (x/z, y/z) of the keypoint.
struct PosedObservation {
  Matrix34d pose_cw;
  Eigen::Vector2d normalized;
};

/// Linear multi-view triangulation (DLT, Hartley & Zisserman 2nd ed. section 12.2): the least
/// squares null vector of the stacked cross-product constraints, each row scaled to unit norm.
/// nullopt for fewer than two observations or a point at infinity.
std::optional<Eigen::Vector3d> triangulateDlt(const std::vector<PosedObservation>& observations);

/// Gauss-Newton refinement of a triangulated point: minimises the squared normalised
/// reprojection errors (a few iterations; the DLT's algebraic error is not geometric).
Eigen::Vector3d refineTriangulation(const std::vector<PosedObservation>& observations,
                                    const Eigen::Vector3d& start, int iterations = 5);

/// Angle at `point` between the rays to two camera centres, radians.
double triangulationAngle(const Eigen::Vector3d& center_a, const Eigen::Vector3d& center_b,
                          const Eigen::Vector3d& point);

/// Depth of `point` in the camera of `pose_cw` (> 0 in front).
inline double depthIn(const Matrix34d& pose_cw, const Eigen::Vector3d& point) {
  return pose_cw.row(2).head<3>().dot(point) + pose_cw(2, 3);
}

}  // namespace auv::recon::sfm
