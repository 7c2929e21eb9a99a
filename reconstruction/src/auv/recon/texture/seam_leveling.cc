#include "auv/recon/texture/seam_leveling.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::texture {

void SeamLevelingOptions::check() const {
  AUV_RECON_CHECK_OPTION(smoothness >= 0, smoothness, "must be >= 0");
  AUV_RECON_CHECK_OPTION(regularization > 0, regularization, "must be > 0");
  AUV_RECON_CHECK_OPTION(samples_per_edge >= 1 && samples_per_edge <= 64, samples_per_edge,
                         "must be in [1, 64]");
}

Eigen::Vector3f ColorOffsets::at(int vertex, int label) const {
  const auto it = offsets.find(key(vertex, label));
  return it == offsets.end() ? Eigen::Vector3f::Zero() : it->second;
}

std::vector<SeamEdge> findSeamEdges(const FaceMesh& mesh, const std::vector<int>& labels) {
  std::unordered_map<uint64_t, int> first_face;  // edge (low, high vertex) -> first face
  first_face.reserve(3 * mesh.faces.size() / 2 + 1);
  std::vector<SeamEdge> seams;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      int a = mesh.faces[f](k), b = mesh.faces[f]((k + 1) % 3);
      if (a > b) std::swap(a, b);
      const auto [it, inserted] = first_face.emplace(
          (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b),
          static_cast<int>(f));
      if (inserted) continue;
      const int g = it->second;
      if (labels[f] == kNoLabel || labels[g] == kNoLabel || labels[f] == labels[g]) continue;
      seams.push_back({a, b, g, static_cast<int>(f), labels[g], labels[f]});
    }
  }
  return seams;
}

SeamLevelingResult levelSeams(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                              const std::vector<int>& labels, const ImageLoader& images,
                              const SeamLevelingOptions& options) {
  options.check();
  SeamLevelingResult result;
  // One variable per (vertex, label) of the labelled faces.
  std::unordered_map<uint64_t, int> variable;
  std::vector<std::pair<int, int>> variable_key;  // (vertex, label)
  auto variableOf = [&](int vertex, int label) {
    const auto [it, inserted] =
        variable.emplace(ColorOffsets::key(vertex, label), static_cast<int>(variable_key.size()));
    if (inserted) variable_key.emplace_back(vertex, label);
    return it->second;
  };
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (labels[f] == kNoLabel) continue;
    for (int k = 0; k < 3; ++k) variableOf(mesh.faces[f](k), labels[f]);
  }
  const size_t n = variable_key.size();
  result.variables = n;
  if (n == 0) return result;

  // f_vl: colours of view l along the seam edges at v (t from 0 at v to 0.5 at the midpoint,
  // weight 1 - t). Requests grouped by view so that each image is loaded once.
  const std::vector<SeamEdge> seams = findSeamEdges(mesh, labels);
  result.seam_edges = seams.size();
  struct Sample {
    int variable;
    Eigen::Vector3d point;
    double weight;
  };
  std::map<int, std::vector<Sample>> samples_by_view;
  for (const SeamEdge& seam : seams) {
    for (const auto& [from, to] :
         {std::make_pair(seam.v0, seam.v1), std::make_pair(seam.v1, seam.v0)}) {
      for (int s = 0; s < options.samples_per_edge; ++s) {
        const double t = 0.5 * s / options.samples_per_edge;
        const Eigen::Vector3d point = (1 - t) * mesh.vertices[from] + t * mesh.vertices[to];
        for (int label : {seam.label_a, seam.label_b}) {
          samples_by_view[label].push_back({variableOf(from, label), point, 1.0 - t});
        }
      }
    }
  }
  std::vector<Eigen::Vector3d> color_sum(n, Eigen::Vector3d::Zero());
  std::vector<double> weight_sum(n, 0.0);
  for (const auto& [view, samples] : samples_by_view) {
    const cv::Mat3b image = images(view);
    if (image.empty()) continue;
    for (const Sample& sample : samples) {
      const Eigen::Vector3d c = views[view].toCamera(sample.point);
      if (c.z() <= 0) continue;
      const Eigen::Vector2d pixel = views[view].project(c);
      color_sum[sample.variable] +=
          sample.weight * sampleBilinear(image, pixel.x(), pixel.y()).cast<double>();
      weight_sum[sample.variable] += sample.weight;
    }
  }

  // Seam terms: every pair of labels meeting at a seam vertex.
  std::map<int, std::vector<int>> labels_at_vertex;  // seam vertices only
  for (const SeamEdge& seam : seams) {
    for (int v : {seam.v0, seam.v1}) {
      for (int label : {seam.label_a, seam.label_b}) labels_at_vertex[v].push_back(label);
    }
  }
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<Eigen::Vector3d> rhs_rows;
  int row = 0;
  double jump_before = 0;
  size_t jump_terms = 0;
  std::vector<std::pair<int, int>> seam_pairs;  // for the residual after
  for (auto& [v, vertex_labels] : labels_at_vertex) {
    std::sort(vertex_labels.begin(), vertex_labels.end());
    vertex_labels.erase(std::unique(vertex_labels.begin(), vertex_labels.end()),
                        vertex_labels.end());
    for (size_t i = 0; i < vertex_labels.size(); ++i) {
      for (size_t j = i + 1; j < vertex_labels.size(); ++j) {
        const int a = variableOf(v, vertex_labels[i]), b = variableOf(v, vertex_labels[j]);
        if (weight_sum[a] <= 0 || weight_sum[b] <= 0) continue;
        const Eigen::Vector3d fa = color_sum[a] / weight_sum[a];
        const Eigen::Vector3d fb = color_sum[b] / weight_sum[b];
        // (f_a + g_a) - (f_b + g_b) = 0  ->  g_a - g_b = f_b - f_a
        triplets.emplace_back(row, a, 1.0);
        triplets.emplace_back(row, b, -1.0);
        rhs_rows.push_back(fb - fa);
        seam_pairs.emplace_back(a, b);
        jump_before += (fa - fb).norm();
        ++jump_terms;
        ++row;
      }
    }
  }
  result.seam_vertices = labels_at_vertex.size();
  // Smoothness inside the patches.
  const double smooth = std::sqrt(options.smoothness);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (labels[f] == kNoLabel || smooth == 0) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = variableOf(mesh.faces[f](k), labels[f]);
      const int b = variableOf(mesh.faces[f]((k + 1) % 3), labels[f]);
      triplets.emplace_back(row, a, smooth);
      triplets.emplace_back(row, b, -smooth);
      rhs_rows.push_back(Eigen::Vector3d::Zero());
      ++row;
    }
  }
  Eigen::SparseMatrix<double> A(row, static_cast<Eigen::Index>(n));
  A.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::MatrixXd b(row, 3);
  for (int r = 0; r < row; ++r) b.row(r) = rhs_rows[r].transpose();
  Eigen::SparseMatrix<double> normal = A.transpose() * A;
  Eigen::SparseMatrix<double> identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  identity.setIdentity();
  normal += options.regularization * identity;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) {
    throw StageError("texture", "seam levelling: the least-squares system could not be factorised");
  }
  const Eigen::MatrixXd g = solver.solve(A.transpose() * b);

  for (size_t i = 0; i < n; ++i) {
    result.offsets.offsets[ColorOffsets::key(variable_key[i].first, variable_key[i].second)] =
        g.row(static_cast<Eigen::Index>(i)).transpose().cast<float>();
  }
  double jump_after = 0;
  for (size_t t = 0; t < seam_pairs.size(); ++t) {
    const auto [a, c] = seam_pairs[t];
    const Eigen::Vector3d fa = color_sum[a] / weight_sum[a] + g.row(a).transpose();
    const Eigen::Vector3d fc = color_sum[c] / weight_sum[c] + g.row(c).transpose();
    jump_after += (fa - fc).norm();
  }
  if (jump_terms > 0) {
    result.mean_jump_before = jump_before / jump_terms;
    result.mean_jump_after = jump_after / jump_terms;
  }
  return result;
}

}  // namespace auv::recon::texture
