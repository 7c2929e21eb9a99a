#include "auv/recon/change/coregistration.h"

#include <cmath>
#include <memory>
#include <sstream>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/RobustKernel.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::change {

namespace registration = open3d::pipelines::registration;
using open3d::geometry::PointCloud;

void CoregistrationOptions::check() const {
  AUV_RECON_CHECK_OPTION(voxel_m > 0, voxel_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(max_correspondence_m > 0, max_correspondence_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(stable_threshold_m > 0, stable_threshold_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(rounds >= 1, rounds, "must be >= 1");
  AUV_RECON_CHECK_OPTION(icp_iterations >= 1, icp_iterations, "must be >= 1");
  AUV_RECON_CHECK_OPTION(min_overlap > 0 && min_overlap <= 1, min_overlap, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(min_stable_fraction > 0 && min_stable_fraction <= 1, min_stable_fraction,
                         "must be in (0, 1]");
}

namespace {

/// Survey 1's surface near each point: the distance along the nearest point's normal, or
/// infinity beyond `reach`.
class Surface {
 public:
  explicit Surface(const PointCloud& cloud) : cloud_(cloud), tree_(cloud) {}
  double distance(const Eigen::Vector3d& point, double reach) const {
    std::vector<int> index;
    std::vector<double> distance2;
    if (tree_.SearchHybrid(point, reach, 1, index, distance2) < 1) {
      return std::numeric_limits<double>::infinity();
    }
    const size_t nearest = static_cast<size_t>(index[0]);
    return std::abs((point - cloud_.points_[nearest]).dot(cloud_.normals_[nearest]));
  }

 private:
  const PointCloud& cloud_;
  open3d::geometry::KDTreeFlann tree_;
};

}  // namespace

CoregistrationResult coregister(const std::vector<Eigen::Vector3d>& cloud1,
                                const std::vector<Eigen::Vector3d>& cloud2,
                                const Eigen::Matrix4d& initial,
                                const CoregistrationOptions& options) {
  options.check();
  if (cloud1.empty() || cloud2.empty()) {
    throw CoregistrationError(std::string("no points in survey ") + (cloud1.empty() ? "1" : "2"));
  }
  const std::shared_ptr<PointCloud> target = PointCloud(cloud1).VoxelDownSample(options.voxel_m);
  // Normals from a few voxels around each point: the surface, not the voxel grid's noise.
  target->EstimateNormals(open3d::geometry::KDTreeSearchParamHybrid(4.0 * options.voxel_m, 30));
  const PointCloud source_all(cloud2);
  const std::shared_ptr<PointCloud> source = source_all.VoxelDownSample(options.voxel_m);
  const Surface surface(*target);

  CoregistrationResult result;
  result.transform = initial;
  std::vector<size_t> stable(source->points_.size());
  for (size_t i = 0; i < stable.size(); ++i) stable[i] = i;
  const registration::TransformationEstimationPointToPlane estimation(
      std::make_shared<registration::TukeyLoss>(options.stable_threshold_m));
  registration::ICPConvergenceCriteria criteria;
  criteria.max_iteration_ = options.icp_iterations;
  size_t overlapping = 0;
  // Distance of a survey-2 point, moved by the current transform, to survey 1's surface.
  const auto residual = [&](const Eigen::Vector3d& point) {
    const Eigen::Vector3d moved =
        result.transform.topLeftCorner<3, 3>() * point + result.transform.topRightCorner<3, 1>();
    return surface.distance(moved, options.max_correspondence_m);
  };
  for (int round = 0; round < options.rounds; ++round) {
    // The first round reaches as far as the coarse transform may be off; later ones only as
    // far as a stable point may be, so changed surfaces find no partner.
    const double reach = round == 0
                             ? options.max_correspondence_m
                             : std::max(2.0 * options.stable_threshold_m, 3.0 * options.voxel_m);
    const std::shared_ptr<PointCloud> stable_source = source->SelectByIndex(stable);
    result.transform = registration::RegistrationICP(*stable_source, *target, reach,
                                                     result.transform, estimation, criteria)
                           .transformation_;
    result.rounds = round + 1;
    // Which points of survey 2 lie on survey 1's surface now.
    stable.clear();
    overlapping = 0;
    for (size_t i = 0; i < source->points_.size(); ++i) {
      const double d = residual(source->points_[i]);
      if (!std::isfinite(d)) continue;
      ++overlapping;
      if (d <= options.stable_threshold_m) stable.push_back(i);
    }
    if (stable.size() < 3) break;
  }
  result.overlap = static_cast<double>(overlapping) / static_cast<double>(source->points_.size());
  result.stable_fraction =
      overlapping > 0 ? static_cast<double>(stable.size()) / static_cast<double>(overlapping) : 0.0;
  if (result.overlap < options.min_overlap) {
    std::ostringstream message;
    message << "the surveys overlap too little: " << 100.0 * result.overlap
            << " % of survey 2 lies within " << options.max_correspondence_m
            << " m of survey 1 after the alignment (min_overlap " << 100.0 * options.min_overlap
            << " %): another site, or a coarse transform off by more than max_correspondence_m";
    throw CoregistrationError(message.str());
  }
  if (result.stable_fraction < options.min_stable_fraction) {
    std::ostringstream message;
    message << "too little stable surface to align on: " << 100.0 * result.stable_fraction
            << " % of the overlap is within " << options.stable_threshold_m
            << " m of survey 1 (min_stable_fraction " << 100.0 * options.min_stable_fraction
            << " %)";
    throw CoregistrationError(message.str());
  }
  // The residual and the stable flags, at full density.
  double sum2 = 0.0;
  size_t count = 0;
  result.stable.assign(cloud2.size(), false);
  for (size_t i = 0; i < cloud2.size(); ++i) {
    const double d = residual(cloud2[i]);
    if (d <= options.stable_threshold_m) {
      result.stable[i] = true;
      sum2 += d * d;
      ++count;
    }
  }
  result.rms_m = count > 0 ? std::sqrt(sum2 / static_cast<double>(count)) : 0.0;
  return result;
}

}  // namespace auv::recon::change
