#include "auv/recon/texture/view_selection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::texture {

void ViewSelectionOptions::check() const {
  AUV_RECON_CHECK_OPTION(min_view_cosine >= 0 && min_view_cosine < 1, min_view_cosine,
                         "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(depth_tolerance > 0 && depth_tolerance < 0.5, depth_tolerance,
                         "must be in (0, 0.5)");
  AUV_RECON_CHECK_OPTION(border_px >= 0, border_px, "must be >= 0");
  AUV_RECON_CHECK_OPTION(gradient_floor >= 0, gradient_floor, "must be >= 0");
  AUV_RECON_CHECK_OPTION(data_term == "gmi" || data_term == "area", data_term,
                         "must be gmi or area");
  AUV_RECON_CHECK_OPTION(photo_consistency_min_views >= 3, photo_consistency_min_views,
                         "must be >= 3 (two views cannot outvote each other)");
  AUV_RECON_CHECK_OPTION(photo_consistency_sigma > 0, photo_consistency_sigma, "must be > 0");
  AUV_RECON_CHECK_OPTION(photo_consistency_threshold > 0 && photo_consistency_threshold < 1,
                         photo_consistency_threshold, "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(smoothness >= 0, smoothness, "must be >= 0");
  AUV_RECON_CHECK_OPTION(max_cycles >= 1, max_cycles, "must be >= 1");
}

void FaceMesh::computeFaceNormals(const std::vector<Eigen::Vector3d>& vertex_normals) {
  face_normals.resize(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Eigen::Vector3i& t = faces[f];
    Eigen::Vector3d n = (vertices[t(1)] - vertices[t(0)]).cross(vertices[t(2)] - vertices[t(0)]);
    const double norm = n.norm();
    n = norm > 0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
    if (vertex_normals.size() == vertices.size()) {
      const Eigen::Vector3d mean =
          vertex_normals[t(0)] + vertex_normals[t(1)] + vertex_normals[t(2)];
      if (n.dot(mean) < 0) n = -n;
    }
    face_normals[f] = n;
  }
}

std::vector<std::pair<int, int>> FaceMesh::faceAdjacency() const {
  std::unordered_map<uint64_t, int> first_face;  // edge (low, high vertex) -> first face
  first_face.reserve(3 * faces.size() / 2 + 1);
  std::vector<std::pair<int, int>> pairs;
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      int a = faces[f]((k + 0) % 3), b = faces[f]((k + 1) % 3);
      if (a > b) std::swap(a, b);
      const auto [it, inserted] = first_face.emplace(
          (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b),
          static_cast<int>(f));
      if (!inserted && it->second != static_cast<int>(f)) {
        pairs.emplace_back(it->second, static_cast<int>(f));
      }
    }
  }
  return pairs;
}

namespace {

/// Calls `visit(x, y)` for the pixel centres inside the 2D triangle (a, b, c) within `size`.
template <class Visit>
void forPixelsIn(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                 const cv::Size& size, Visit&& visit) {
  const int x_min = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
  const int x_max =
      std::min(size.width - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
  const int y_min = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
  const int y_max =
      std::min(size.height - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
  Eigen::Vector3d w;
  for (int y = y_min; y <= y_max; ++y) {
    for (int x = x_min; x <= x_max; ++x) {
      if (!barycentric2d(a, b, c, Eigen::Vector2d(x, y), w)) return;
      if (w.minCoeff() >= -1e-9) visit(x, y);
    }
  }
}

/// The observations of one view.
std::vector<std::pair<int, FaceObservation>> observeInView(const FaceMesh& mesh,
                                                           const ViewGeometry& view, int view_id,
                                                           const cv::Mat3b& image,
                                                           const cv::Mat1b& mask,
                                                           const ViewSelectionOptions& options) {
  std::vector<std::pair<int, FaceObservation>> seen;
  const RasterBuffers buffers = rasterize(mesh.vertices, mesh.faces, view);
  cv::Mat1f gradient;
  {
    cv::Mat grey, gx, gy;
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(grey, CV_32F);
    cv::Sobel(grey, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);  // grey levels per pixel
    cv::Sobel(grey, gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
    cv::magnitude(gx, gy, gradient);
  }
  const Eigen::Vector3d center = view.center();
  const double x_max = view.width() - 1 - options.border_px;
  const double y_max = view.height() - 1 - options.border_px;
  const cv::Size size(view.width(), view.height());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    const Eigen::Vector3d& v0 = mesh.vertices[t(0)];
    const Eigen::Vector3d& v1 = mesh.vertices[t(1)];
    const Eigen::Vector3d& v2 = mesh.vertices[t(2)];
    const Eigen::Vector3d centroid = (v0 + v1 + v2) / 3.0;
    const Eigen::Vector3d to_camera = (center - centroid).normalized();
    if (mesh.face_normals[f].dot(to_camera) <= options.min_view_cosine) continue;
    const Eigen::Vector3d c0 = view.toCamera(v0), c1 = view.toCamera(v1), c2 = view.toCamera(v2);
    if (c0.z() <= 1e-3 || c1.z() <= 1e-3 || c2.z() <= 1e-3) continue;
    const Eigen::Vector2d p0 = view.project(c0), p1 = view.project(c1), p2 = view.project(c2);
    bool inside = true;
    for (const Eigen::Vector2d* p : {&p0, &p1, &p2}) {
      if (p->x() < options.border_px || p->y() < options.border_px || p->x() > x_max ||
          p->y() > y_max) {
        inside = false;
      }
    }
    if (!inside) continue;
    // Occlusion: the centroid and the corners pulled 10 % towards it must all be in front of
    // (or on) the z-buffer; the whole face must be visible.
    bool visible = true;
    for (int k = 0; k < 4 && visible; ++k) {
      const Eigen::Vector3d point =
          k == 3 ? centroid : Eigen::Vector3d(0.9 * mesh.vertices[t(k)] + 0.1 * centroid);
      const Eigen::Vector3d camera_point = view.toCamera(point);
      const Eigen::Vector2d pixel = view.project(camera_point);
      const int x = static_cast<int>(std::lround(pixel.x()));
      const int y = static_cast<int>(std::lround(pixel.y()));
      if (buffers.face(y, x) == static_cast<int>(f)) continue;
      if (camera_point.z() > buffers.depth(y, x) * (1.0 + options.depth_tolerance)) {
        visible = false;
      }
    }
    if (!visible) continue;

    FaceObservation observation;
    observation.view = view_id;
    observation.area_px = static_cast<float>(
        0.5 * std::abs((p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x()));
    double gmi = 0;
    Eigen::Vector3d color_sum = Eigen::Vector3d::Zero();
    int pixels = 0;
    bool masked = false;
    forPixelsIn(p0, p1, p2, size, [&](int x, int y) {
      if (!mask.empty() && mask(y, x) == 0) masked = true;
      gmi += gradient(y, x);
      const cv::Vec3b& c = image(y, x);
      color_sum += Eigen::Vector3d(c[0], c[1], c[2]);
      ++pixels;
    });
    if (pixels == 0) {  // smaller than a pixel: sample its centre
      const Eigen::Vector2d m = (p0 + p1 + p2) / 3.0;
      const int mx = std::clamp(static_cast<int>(std::lround(m.x())), 0, size.width - 1);
      const int my = std::clamp(static_cast<int>(std::lround(m.y())), 0, size.height - 1);
      if (!mask.empty() && mask(my, mx) == 0) masked = true;
      color_sum = sampleBilinear(image, m.x(), m.y()).cast<double>();
      gmi = observation.area_px *
            gradient(static_cast<int>(std::lround(m.y())), static_cast<int>(std::lround(m.x())));
      pixels = 1;
    } else {
      gmi *= observation.area_px / pixels;  // the integral over the exact projected area
    }
    if (masked) continue;
    observation.mean_color = (color_sum / pixels).cast<float>();
    observation.quality =
        options.data_term == "area"
            ? observation.area_px
            : static_cast<float>(gmi + options.gradient_floor * observation.area_px);
    if (observation.quality <= 0) continue;
    seen.emplace_back(static_cast<int>(f), observation);
  }
  return seen;
}

}  // namespace

std::vector<std::vector<FaceObservation>> observeFaces(const FaceMesh& mesh,
                                                       const std::vector<ViewGeometry>& views,
                                                       const ImageLoader& images,
                                                       const ViewSelectionOptions& options,
                                                       const ImageLoader& masks) {
  options.check();
  std::vector<std::vector<std::pair<int, FaceObservation>>> per_view(views.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t v = 0; v < views.size(); ++v) {
    cv::Mat image = images(static_cast<int>(v));
    if (image.type() != CV_8UC3 || image.cols != views[v].width() ||
        image.rows != views[v].height()) {
      continue;  // the loader reports bad images; a view without image sees nothing
    }
    cv::Mat mask = masks ? masks(static_cast<int>(v)) : cv::Mat();
    if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != image.size())) mask.release();
    per_view[v] = observeInView(mesh, views[v], static_cast<int>(v), image, mask, options);
  }
  std::vector<std::vector<FaceObservation>> observations(mesh.faces.size());
  for (auto& seen : per_view) {  // in view order: each face's list is sorted by view
    for (auto& [face, observation] : seen) observations[face].push_back(observation);
  }
  return observations;
}

size_t rejectInconsistentViews(std::vector<std::vector<FaceObservation>>& observations,
                               const ViewSelectionOptions& options) {
  size_t rejected = 0;
  const double log_threshold = std::log(options.photo_consistency_threshold);
  const size_t min_views = static_cast<size_t>(options.photo_consistency_min_views);
  // Exposure and white balance differ between views (the seam levelling evens them out later):
  // each view's gain per channel is the median ratio of its colours of the faces to their
  // per-face medians; colours are compared after dividing by it.
  int num_views = 0;
  for (const auto& face : observations) {
    for (const auto& o : face) num_views = std::max(num_views, o.view + 1);
  }
  std::vector<std::array<std::vector<float>, 3>> ratios(num_views);
  std::vector<float> channel;
  for (const auto& face : observations) {
    if (face.size() < min_views) continue;
    for (int c = 0; c < 3; ++c) {
      channel.clear();
      for (const auto& o : face) channel.push_back(o.mean_color(c));
      std::nth_element(channel.begin(), channel.begin() + channel.size() / 2, channel.end());
      const float median = channel[channel.size() / 2];
      if (median < 8.0f) continue;  // too dark for a ratio
      for (const auto& o : face) ratios[o.view][c].push_back(o.mean_color(c) / median);
    }
  }
  std::vector<Eigen::Vector3f> gain(num_views, Eigen::Vector3f::Ones());
  for (int v = 0; v < num_views; ++v) {
    for (int c = 0; c < 3; ++c) {
      auto& r = ratios[v][c];
      if (r.size() < 10) continue;
      std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
      gain[v](c) = std::clamp(r[r.size() / 2], 0.25f, 4.0f);
    }
  }
  for (auto& face : observations) {
    const size_t n = face.size();
    if (n < min_views) continue;
    std::vector<Eigen::Vector3f> colors(n);
    for (size_t i = 0; i < n; ++i) colors[i] = face[i].mean_color.cwiseQuotient(gain[face[i].view]);
    // Start at the per-channel median; bandwidth from the median absolute deviation.
    Eigen::Vector3d mode, sigma;
    std::vector<double> values(n);
    for (int c = 0; c < 3; ++c) {
      for (size_t i = 0; i < n; ++i) values[i] = colors[i](c);
      std::nth_element(values.begin(), values.begin() + n / 2, values.end());
      mode(c) = values[n / 2];
      for (size_t i = 0; i < n; ++i) values[i] = std::abs(colors[i](c) - mode(c));
      std::nth_element(values.begin(), values.begin() + n / 2, values.end());
      sigma(c) = std::max(options.photo_consistency_sigma, 1.4826 * values[n / 2]);
    }
    auto logWeight = [&](const Eigen::Vector3f& color) {
      const Eigen::Vector3d d = (color.cast<double>() - mode).cwiseQuotient(sigma);
      return -0.5 * d.squaredNorm();
    };
    // Mean-shift with a Gaussian kernel: the mode of the views' colours.
    for (int iteration = 0; iteration < 20; ++iteration) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double weights = 0;
      for (const auto& color : colors) {
        const double w = std::exp(logWeight(color));
        sum += w * color.cast<double>();
        weights += w;
      }
      if (weights <= 1e-300) break;
      const Eigen::Vector3d next = sum / weights;
      const double shift = (next - mode).norm();
      mode = next;
      if (shift < 1e-3) break;
    }
    std::vector<FaceObservation> kept;
    for (size_t i = 0; i < n; ++i) {
      if (logWeight(colors[i]) >= log_threshold) kept.push_back(face[i]);
    }
    if (kept.empty()) continue;  // no consensus: keep them all
    rejected += face.size() - kept.size();
    face = std::move(kept);
  }
  return rejected;
}

PottsProblem buildLabelingProblem(const std::vector<std::vector<FaceObservation>>& observations,
                                  const std::vector<std::pair<int, int>>& adjacency,
                                  const ViewSelectionOptions& options) {
  PottsProblem problem;
  problem.smoothness = options.smoothness;
  problem.edges = adjacency;
  problem.costs.resize(observations.size());
  for (size_t f = 0; f < observations.size(); ++f) {
    float best = 0;
    for (const auto& o : observations[f]) best = std::max(best, o.quality);
    for (const auto& o : observations[f]) {
      problem.costs[f].emplace_back(o.view, best > 0 ? 1.0f - o.quality / best : 1.0f);
    }
  }
  return problem;
}

ViewSelectionResult selectViews(const std::vector<std::vector<FaceObservation>>& observations,
                                const std::vector<std::pair<int, int>>& adjacency,
                                const ViewSelectionOptions& options) {
  options.check();
  const PottsProblem problem = buildLabelingProblem(observations, adjacency, options);
  ViewSelectionResult result;
  const std::vector<int> greedy = greedyLabels(problem);
  result.greedy_energy = energy(problem, greedy);
  result.greedy_seams = countSeams(problem, greedy);
  if (options.use_mrf) {
    ExpansionResult expansion = alphaExpansion(problem, greedy, options.max_cycles);
    result.labels = std::move(expansion.labels);
    result.energy = expansion.energy;
    result.cycles = expansion.cycles;
  } else {
    result.labels = greedy;
    result.energy = result.greedy_energy;
  }
  result.seams = countSeams(problem, result.labels);
  return result;
}

}  // namespace auv::recon::texture
