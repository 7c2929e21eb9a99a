#include "auv/recon/dense/neighbours.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::dense {

void NeighbourOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_neighbours >= 1, max_neighbours, "must be >= 1");
  AUV_RECON_CHECK_OPTION(min_shared_points >= 1, min_shared_points, "must be >= 1");
  AUV_RECON_CHECK_OPTION(min_angle_deg >= 0, min_angle_deg, "must be >= 0");
  AUV_RECON_CHECK_OPTION(max_angle_deg > min_angle_deg && max_angle_deg <= 180, max_angle_deg,
                         "must be in (min_angle_deg, 180]");
  AUV_RECON_CHECK_OPTION(good_angle_deg > 0, good_angle_deg, "must be > 0");
  AUV_RECON_CHECK_OPTION(depth_percentile >= 0 && depth_percentile < 0.5, depth_percentile,
                         "must be in [0, 0.5)");
  AUV_RECON_CHECK_OPTION(depth_margin >= 0 && depth_margin < 1, depth_margin, "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(min_depth_points >= 2, min_depth_points, "must be >= 2");
}

namespace {
constexpr double kRadToDeg = 180.0 / M_PI;

double median(std::vector<double>& values) {
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}
}  // namespace

std::vector<MasterSelection> selectNeighbours(const scene::Reconstruction& model,
                                              const NeighbourOptions& options) {
  options.check();
  std::vector<MasterSelection> selections;
  selections.reserve(model.images.size());
  for (const auto& [master_id, master] : model.images) {
    MasterSelection selection;
    selection.master = master_id;
    const Eigen::Vector3d master_center = master.center();
    // Angles of the rays to every shared point, per other image.
    std::unordered_map<uint32_t, std::vector<double>> angles;
    std::vector<double> depths;
    for (const int64_t point_id : master.point3d_ids) {
      if (point_id == scene::kNoPoint3D) continue;
      const auto point = model.points.find(static_cast<uint64_t>(point_id));
      if (point == model.points.end()) continue;
      const Eigen::Vector3d& xyz = point->second.xyz;
      const double depth = master.toCamera(xyz).z();
      if (depth <= 0) continue;
      depths.push_back(depth);
      const Eigen::Vector3d ray_master = (xyz - master_center).normalized();
      uint32_t last_image = master_id;  // a track may hold an image twice; count it once
      for (const scene::TrackElement& element : point->second.track) {
        if (element.image_id == master_id || element.image_id == last_image) continue;
        last_image = element.image_id;
        const auto other = model.images.find(element.image_id);
        if (other == model.images.end()) continue;
        const Eigen::Vector3d ray_other = (xyz - other->second.center()).normalized();
        const double cosine = std::clamp(ray_master.dot(ray_other), -1.0, 1.0);
        angles[element.image_id].push_back(std::acos(cosine) * kRadToDeg);
      }
    }
    selection.depth_points = depths.size();
    if (static_cast<int>(depths.size()) >= options.min_depth_points) {
      std::sort(depths.begin(), depths.end());
      const size_t cut = static_cast<size_t>(options.depth_percentile * depths.size());
      const double low = depths[cut], high = depths[depths.size() - 1 - cut];
      selection.depth_min = low * (1.0 - options.depth_margin);
      selection.depth_max = high * (1.0 + options.depth_margin);
    }
    struct Candidate {
      uint32_t id;
      int shared;
      double angle, score;
    };
    std::vector<Candidate> candidates;
    for (auto& [other_id, other_angles] : angles) {
      const int shared = static_cast<int>(other_angles.size());
      if (shared < options.min_shared_points) continue;
      const double angle = median(other_angles);
      if (angle < options.min_angle_deg || angle > options.max_angle_deg) continue;
      const double weight = std::min(1.0, angle / options.good_angle_deg);
      candidates.push_back({other_id, shared, angle, shared * weight * weight});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.score != b.score ? a.score > b.score : a.id < b.id;
    });
    if (static_cast<int>(candidates.size()) > options.max_neighbours) {
      candidates.resize(options.max_neighbours);
    }
    for (const Candidate& c : candidates) {
      selection.neighbours.push_back(c.id);
      selection.shared_points.push_back(c.shared);
      selection.angle_deg.push_back(c.angle);
    }
    selections.push_back(std::move(selection));
  }
  return selections;
}

}  // namespace auv::recon::dense
