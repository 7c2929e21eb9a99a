#pragma once
// M3C2, the Multiscale Model to Model Cloud Comparison of Lague, Brodu & Leroux (2013): the
// signed distance between two point clouds of one site, measured at core points along a local
// surface normal, with a level of detection from the local roughness, the point counts and the
// registration error. Change is significant where |distance| exceeds that level.
//
// At each core point: the normal is the least-squares plane's of cloud 1 within normal_scale/2
// (both clouds where cloud 1 has too few points there), oriented towards a hint; each cloud's
// points inside the projection cylinder (radius projection_scale/2, half-length max_depth,
// along the normal) give a mean position along the axis and its spread; the distance is
// mean 2 - mean 1 and the level of detection at 95 %
//   LoD = z (sqrt(s1²/n1 + s2²/n2) + registration_error),  z = 1.96,
// as in the paper's Eq. (1), py4dgeo and CloudCompare's plugin.
//
// n counts independent measurements. A laser scanner's points are; a photogrammetric cloud's
// are not: the points of one depth map share its error, so hundreds of fused points in a
// cylinder may rest on five images and σ/√n would promise a precision they do not have. When
// each point's sources are given (the images fused into it, dense/fused_views.bin), n is the
// number of distinct sources in the cylinder (at most its point count).
//
// A cylinder may also take in a surface that does not cross it: beside a fallen block lying
// against a wall, the wall's horizontal cylinders pass over the block's top, whose points spread
// along the axis and whose mean along it is no displacement (Lague's M3C2, py4dgeo and
// CloudCompare's plugin have no guard). When a cloud's point normals are given, a point counts
// only where its own normal is within max_axis_angle_deg of the axis: its surface crosses the
// cylinder.
#include <algorithm>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/dense/fusion.h"

namespace auv::recon::change {

struct M3C2Options {
  double normal_scale_m = 1.0;      ///< D: diameter of the neighbourhood the normal is fitted to
  double projection_scale_m = 0.5;  ///< d: diameter of the projection cylinder
  double max_depth_m = 1.0;         ///< half-length of the cylinder along the normal
  int min_points = 5;               ///< fewer points of a cloud in the cylinder: no distance there
  /// m, the co-registration's error, added inside the level of detection (Lague's "reg").
  double registration_error_m = 0.0;
  double confidence_z = 1.96;  ///< two-sided normal quantile of the level of detection (95 %)
  /// deg: a point with a normal farther than this from the cylinder's axis lies on a surface
  /// along it and is not counted (90: every point counts, as in Lague's M3C2). Applies where
  /// the cloud's normals are given.
  double max_axis_angle_deg = 60.0;
  /// Orientation of the normals where no per-point hint is given: they point to its side.
  Eigen::Vector3d orientation = Eigen::Vector3d(0, 0, -1);  ///< NED: up

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// The comparison at one core point. `distance` and `level_of_detection` are NaN where a
/// cloud had fewer than min_points in the cylinder or no normal could be fitted.
struct M3C2Point {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double distance = std::numeric_limits<double>::quiet_NaN();            ///< m, cloud 2 - cloud 1
  double level_of_detection = std::numeric_limits<double>::quiet_NaN();  ///< m
  double spread1 = 0.0, spread2 = 0.0;  ///< m, standard deviations along the normal
  int count1 = 0, count2 = 0;           ///< points in the cylinder
  /// Distinct sources (images) of those points; 0 when the cloud's sources were not given.
  int sources1 = 0, sources2 = 0;
  bool significant = false;  ///< |distance| > level_of_detection

  bool valid() const { return distance == distance; }
  /// The n of the level of detection: the sources where known, else the points.
  int independent1() const { return sources1 > 0 ? std::min(count1, sources1) : count1; }
  int independent2() const { return sources2 > 0 ? std::min(count2, sources2) : count2; }
};

/// Per point of a cloud, the ids of the independent measurements it came from (for a fused
/// MVS cloud, the images whose depth maps gave it).
using PointSources = dense::PointViews;

/// z (sqrt(s1²/n1 + s2²/n2) + registration_error) with n the independent measurements: the
/// level of detection of a measured point.
double levelOfDetection(const M3C2Point& p, double registration_error_m, double confidence_z);

/// One cloud of the comparison and what is known of its points.
struct M3C2Cloud {
  const std::vector<Eigen::Vector3d>& points;
  /// Per point, its independent measurements: n is then the distinct ones (see above).
  const PointSources* sources = nullptr;
  /// Per point, its surface's unit normal (either side): points of surfaces along a cylinder
  /// are then not counted in it (see above).
  const std::vector<Eigen::Vector3d>* normals = nullptr;
};

/// M3C2 of `cloud2` against `cloud1` at `core_points`. `orientation_hints`, when not empty (one
/// per core point), gives each normal's side (e.g. towards the cameras that saw the point);
/// otherwise options.orientation does. Throws OptionError on bad options and
/// std::invalid_argument when the hints, sources or normals do not match the core points or
/// clouds.
std::vector<M3C2Point> m3c2(const M3C2Cloud& cloud1, const M3C2Cloud& cloud2,
                            const std::vector<Eigen::Vector3d>& core_points,
                            const M3C2Options& options,
                            const std::vector<Eigen::Vector3d>& orientation_hints = {});

/// The same without point normals; `sources1`/`sources2` as M3C2Cloud::sources.
std::vector<M3C2Point> m3c2(const std::vector<Eigen::Vector3d>& cloud1,
                            const std::vector<Eigen::Vector3d>& cloud2,
                            const std::vector<Eigen::Vector3d>& core_points,
                            const M3C2Options& options,
                            const std::vector<Eigen::Vector3d>& orientation_hints = {},
                            const PointSources* sources1 = nullptr,
                            const PointSources* sources2 = nullptr);

}  // namespace auv::recon::change
