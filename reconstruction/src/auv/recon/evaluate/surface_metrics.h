#pragma once
// Accuracy, completeness and F-score of a reconstructed surface against the true one, as in
// Tanks and Temples (Knapitsch et al., SIGGRAPH 2017, section 4): at a distance threshold t,
//   precision P(t) = fraction of reconstructed points within t of the true surface,
//   recall    R(t) = fraction of true-surface samples within t of the reconstruction,
//   F(t) = 2 P R / (P + R).
// Both are restricted to the well-imaged region (well_imaged_region.h): a reconstructed point
// counts when the true-surface sample nearest to it is well imaged, and recall runs over the
// well-imaged samples only. Distances to the true surface are exact point-to-triangle
// distances (Open3D RaycastingScene::ComputeDistance); to a reconstructed cloud, nearest
// neighbours (Open3D KDTreeFlann); to a reconstructed mesh, point-to-triangle distances.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace open3d::geometry {
class TriangleMesh;
}

namespace auv::recon::evaluate {

struct ThresholdScore {
  double threshold_m = 0;
  double precision = 0, recall = 0, fscore = 0;
};

struct SurfaceScores {
  size_t points_evaluated = 0;   ///< reconstructed points in the region (precision's base)
  size_t points_outside = 0;     ///< reconstructed points left out (nearest sample not well imaged)
  size_t samples_evaluated = 0;  ///< well-imaged true samples (recall's base)
  double mean_accuracy_m = 0, median_accuracy_m = 0;          ///< reconstruction -> truth
  double mean_completeness_m = 0, median_completeness_m = 0;  ///< truth -> reconstruction
  std::vector<ThresholdScore> scores;
};

/// Scores from the two sets of distances (pure arithmetic, the definition above).
SurfaceScores scoreDistances(const std::vector<double>& reconstruction_to_truth,
                             const std::vector<double>& truth_to_reconstruction,
                             const std::vector<double>& thresholds_m);

/// Distance of each point to the nearest triangle of `mesh`.
std::vector<double> distancesToMesh(const std::vector<Eigen::Vector3d>& points,
                                    const open3d::geometry::TriangleMesh& mesh);

/// Distance of each query to the nearest of `points` (infinity when `points` is empty).
std::vector<double> distancesToPoints(const std::vector<Eigen::Vector3d>& queries,
                                      const std::vector<Eigen::Vector3d>& points);

/// Index of the nearest of `points` for each query.
std::vector<int> nearestIndices(const std::vector<Eigen::Vector3d>& queries,
                                const std::vector<Eigen::Vector3d>& points);

/// The whole comparison of one reconstruction (a cloud, or samples of a mesh with the mesh
/// itself for the recall distances) with the true surface.
///   truth_mesh:       the world mesh (precision distances)
///   truth_samples:    samples of it near the cameras, `well_imaged` flags per sample
///   points:           reconstructed points (already in the truth's frame)
///   reconstruction_mesh: when not null, recall distances go to this surface instead of the
///                     points
SurfaceScores scoreSurface(const open3d::geometry::TriangleMesh& truth_mesh,
                           const std::vector<Eigen::Vector3d>& truth_samples,
                           const std::vector<bool>& well_imaged,
                           const std::vector<Eigen::Vector3d>& points,
                           const open3d::geometry::TriangleMesh* reconstruction_mesh,
                           const std::vector<double>& thresholds_m);

}  // namespace auv::recon::evaluate
