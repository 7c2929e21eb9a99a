#include "auv/recon/evaluate/surface_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <open3d/core/Tensor.h>
#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/t/geometry/RaycastingScene.h>

#include "auv/recon/evaluate/alignment.h"

namespace auv::recon::evaluate {
namespace {

Eigen::MatrixXd toMatrix(const std::vector<Eigen::Vector3d>& points) {
  Eigen::MatrixXd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

double mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double fractionWithin(const std::vector<double>& distances, double threshold) {
  if (distances.empty()) return 0.0;
  size_t within = 0;
  for (double d : distances) within += d <= threshold ? 1 : 0;
  return static_cast<double>(within) / static_cast<double>(distances.size());
}

}  // namespace

SurfaceScores scoreDistances(const std::vector<double>& reconstruction_to_truth,
                             const std::vector<double>& truth_to_reconstruction,
                             const std::vector<double>& thresholds_m) {
  SurfaceScores s;
  s.points_evaluated = reconstruction_to_truth.size();
  s.samples_evaluated = truth_to_reconstruction.size();
  s.mean_accuracy_m = mean(reconstruction_to_truth);
  s.median_accuracy_m = median(reconstruction_to_truth);
  s.mean_completeness_m = mean(truth_to_reconstruction);
  s.median_completeness_m = median(truth_to_reconstruction);
  for (double t : thresholds_m) {
    ThresholdScore score;
    score.threshold_m = t;
    score.precision = fractionWithin(reconstruction_to_truth, t);
    score.recall = fractionWithin(truth_to_reconstruction, t);
    const double sum = score.precision + score.recall;
    score.fscore = sum > 0 ? 2.0 * score.precision * score.recall / sum : 0.0;
    s.scores.push_back(score);
  }
  return s;
}

std::vector<double> distancesToMesh(const std::vector<Eigen::Vector3d>& points,
                                    const open3d::geometry::TriangleMesh& mesh) {
  std::vector<double> distances(points.size(), std::numeric_limits<double>::infinity());
  if (points.empty() || mesh.triangles_.empty()) return distances;
  namespace core = open3d::core;
  std::vector<float> vertices(3 * mesh.vertices_.size());
  for (size_t i = 0; i < mesh.vertices_.size(); ++i) {
    for (int j = 0; j < 3; ++j) vertices[3 * i + j] = static_cast<float>(mesh.vertices_[i](j));
  }
  // Triangles degenerate in float (zero area: collinear or coincident corners, as Poisson
  // meshes have a few of) are left out: Open3D 0.16's closest-point query turns them into NaN
  // and aborts on an internal assertion. They add no surface, so no distance changes.
  std::vector<uint32_t> triangles;
  triangles.reserve(3 * mesh.triangles_.size());
  auto corner = [&](int index) { return Eigen::Map<const Eigen::Vector3f>(&vertices[3 * index]); };
  for (const Eigen::Vector3i& t : mesh.triangles_) {
    const Eigen::Vector3f a = corner(t(0)), b = corner(t(1)), c = corner(t(2));
    const float twice_area = (b - a).cross(c - a).norm();
    if (!(twice_area > 0.0f) || !std::isfinite(twice_area)) continue;
    for (int j = 0; j < 3; ++j) triangles.push_back(static_cast<uint32_t>(t(j)));
  }
  if (triangles.empty()) return distances;
  open3d::t::geometry::RaycastingScene scene;
  scene.AddTriangles(
      core::Tensor(vertices, {static_cast<int64_t>(mesh.vertices_.size()), 3}, core::Float32),
      core::Tensor(triangles, {static_cast<int64_t>(triangles.size() / 3), 3}, core::UInt32));
  // In blocks, so the float copies stay small for clouds of millions of points.
  constexpr size_t kBlock = 1 << 20;
  std::vector<float> query;
  for (size_t begin = 0; begin < points.size(); begin += kBlock) {
    const size_t end = std::min(points.size(), begin + kBlock);
    query.resize(3 * (end - begin));
    for (size_t i = begin; i < end; ++i) {
      for (int j = 0; j < 3; ++j) query[3 * (i - begin) + j] = static_cast<float>(points[i](j));
    }
    const core::Tensor result = scene.ComputeDistance(
        core::Tensor(query, {static_cast<int64_t>(end - begin), 3}, core::Float32));
    const float* d = result.GetDataPtr<float>();
    for (size_t i = begin; i < end; ++i) distances[i] = d[i - begin];
  }
  return distances;
}

std::vector<int> nearestIndices(const std::vector<Eigen::Vector3d>& queries,
                                const std::vector<Eigen::Vector3d>& points) {
  std::vector<int> nearest(queries.size(), -1);
  if (points.empty()) return nearest;
  // Open3D 0.16 keeps referring to the matrix it was built from: it must outlive the tree.
  const Eigen::MatrixXd tree_data = toMatrix(points);
  const open3d::geometry::KDTreeFlann tree(tree_data);
#pragma omp parallel for schedule(dynamic, 1024)
  for (int64_t i = 0; i < static_cast<int64_t>(queries.size()); ++i) {
    std::vector<int> index(1);
    std::vector<double> distance2(1);
    if (tree.SearchKNN(queries[i], 1, index, distance2) > 0) nearest[i] = index[0];
  }
  return nearest;
}

std::vector<double> distancesToPoints(const std::vector<Eigen::Vector3d>& queries,
                                      const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> distances(queries.size(), std::numeric_limits<double>::infinity());
  const std::vector<int> nearest = nearestIndices(queries, points);
  for (size_t i = 0; i < queries.size(); ++i) {
    if (nearest[i] >= 0) distances[i] = (queries[i] - points[nearest[i]]).norm();
  }
  return distances;
}

SurfaceScores scoreSurface(const open3d::geometry::TriangleMesh& truth_mesh,
                           const std::vector<Eigen::Vector3d>& truth_samples,
                           const std::vector<bool>& well_imaged,
                           const std::vector<Eigen::Vector3d>& points,
                           const open3d::geometry::TriangleMesh* reconstruction_mesh,
                           const std::vector<double>& thresholds_m) {
  if (well_imaged.size() != truth_samples.size()) {
    throw std::invalid_argument("scoreSurface: one well_imaged flag per truth sample expected");
  }
  // Precision over the reconstructed points whose nearest true sample is well imaged.
  const std::vector<int> nearest = nearestIndices(points, truth_samples);
  std::vector<Eigen::Vector3d> inside;
  for (size_t i = 0; i < points.size(); ++i) {
    if (nearest[i] >= 0 && well_imaged[nearest[i]]) inside.push_back(points[i]);
  }
  const std::vector<double> precision_distances = distancesToMesh(inside, truth_mesh);

  // Recall over the well-imaged samples.
  std::vector<Eigen::Vector3d> region;
  for (size_t i = 0; i < truth_samples.size(); ++i) {
    if (well_imaged[i]) region.push_back(truth_samples[i]);
  }
  const std::vector<double> recall_distances = reconstruction_mesh
                                                   ? distancesToMesh(region, *reconstruction_mesh)
                                                   : distancesToPoints(region, points);
  SurfaceScores scores = scoreDistances(precision_distances, recall_distances, thresholds_m);
  scores.points_outside = points.size() - inside.size();
  return scores;
}

}  // namespace auv::recon::evaluate
