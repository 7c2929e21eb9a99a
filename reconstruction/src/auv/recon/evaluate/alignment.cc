#include "auv/recon/evaluate/alignment.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::evaluate {
namespace {

/// Points of one image: its centre and, when `axis_length` > 0, the centre moved along the
/// camera's x and z axes (in the reconstruction by axis_length / scale, so both sets span the
/// same length in the truth's units once aligned).
struct ImagePoints {
  Eigen::Matrix3Xd estimate, truth;
};

ImagePoints imagePoints(const PosePair& pair, double axis_length, double scale) {
  const int count = axis_length > 0 ? 3 : 1;
  ImagePoints p{Eigen::Matrix3Xd(3, count), Eigen::Matrix3Xd(3, count)};
  p.estimate.col(0) = pair.center_estimate;
  p.truth.col(0) = pair.center_truth;
  if (count == 3) {
    const double estimate_length = axis_length / scale;
    // Rows of a world -> camera rotation are the camera axes in the world.
    p.estimate.col(1) =
        pair.center_estimate + estimate_length * pair.rotation_estimate_cw.row(0).transpose();
    p.estimate.col(2) =
        pair.center_estimate + estimate_length * pair.rotation_estimate_cw.row(2).transpose();
    p.truth.col(1) = pair.center_truth + axis_length * pair.rotation_truth_cw.row(0).transpose();
    p.truth.col(2) = pair.center_truth + axis_length * pair.rotation_truth_cw.row(2).transpose();
  }
  return p;
}

Similarity fromMatrix(const Eigen::Matrix4d& T) {
  Similarity s;
  const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
  s.scale = std::cbrt(sR.determinant());
  s.rotation = sR / s.scale;
  s.translation = T.topRightCorner<3, 1>();
  return s;
}

/// Umeyama on the points of `images`; false when the points do not fix a similarity.
bool fit(const std::vector<ImagePoints>& points, const std::vector<size_t>& images,
         Similarity& out) {
  size_t columns = 0;
  for (size_t i : images) columns += points[i].estimate.cols();
  Eigen::Matrix3Xd src(3, columns), dst(3, columns);
  size_t c = 0;
  for (size_t i : images) {
    const auto n = points[i].estimate.cols();
    src.middleCols(c, n) = points[i].estimate;
    dst.middleCols(c, n) = points[i].truth;
    c += n;
  }
  // Degenerate when the source points are (nearly) collinear: the second singular value of
  // their spread vanishes against the first.
  const Eigen::Matrix3Xd centred = src.colwise() - src.rowwise().mean();
  const Eigen::Vector3d sv =
      Eigen::JacobiSVD<Eigen::Matrix3d>(centred * centred.transpose()).singularValues();
  if (!(sv(0) > 0) || sv(1) < 1e-10 * sv(0)) return false;
  out = fromMatrix(Eigen::umeyama(src, dst, true));
  return std::isfinite(out.scale) && out.scale > 0;
}

/// Residual of one image: RMS distance of its aligned points to the true ones (truth units).
double residual(const ImagePoints& p, const Similarity& s) {
  double sum = 0;
  for (int j = 0; j < p.estimate.cols(); ++j) {
    sum += (s.apply(p.estimate.col(j)) - p.truth.col(j)).squaredNorm();
  }
  return std::sqrt(sum / p.estimate.cols());
}

/// Robust initial scale: the median ratio of true to estimated distances between centres.
double initialScale(const std::vector<PosePair>& pairs, std::mt19937_64& rng, int trials) {
  std::vector<double> ratios;
  const size_t n = pairs.size();
  auto add = [&](size_t i, size_t j) {
    const double de = (pairs[i].center_estimate - pairs[j].center_estimate).norm();
    const double dt = (pairs[i].center_truth - pairs[j].center_truth).norm();
    if (de > 1e-12 && dt > 1e-12) ratios.push_back(dt / de);
  };
  if (n * (n - 1) / 2 <= static_cast<size_t>(trials)) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) add(i, j);
  } else {
    std::uniform_int_distribution<size_t> pick(0, n - 1);
    for (int t = 0; t < trials; ++t) {
      const size_t i = pick(rng), j = pick(rng);
      if (i != j) add(i, j);
    }
  }
  return ratios.empty() ? 0.0 : median(ratios);
}

}  // namespace

Eigen::Matrix4d Similarity::matrix() const {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = scale * rotation;
  T.topRightCorner<3, 1>() = translation;
  return T;
}

Similarity Similarity::inverse() const {
  Similarity inv;
  inv.scale = 1.0 / scale;
  inv.rotation = rotation.transpose();
  inv.translation = -(inv.scale * (inv.rotation * translation));
  return inv;
}

void AlignmentOptions::check() const {
  AUV_RECON_CHECK_OPTION(axis_length_m >= 0 && std::isfinite(axis_length_m), axis_length_m,
                         "must be >= 0 m (0 = camera centres only)");
  AUV_RECON_CHECK_OPTION(max_trials >= 1, max_trials, "must be >= 1");
  AUV_RECON_CHECK_OPTION(inlier_sigmas > 0, inlier_sigmas, "must be > 0");
  AUV_RECON_CHECK_OPTION(min_inlier_m >= 0, min_inlier_m, "must be >= 0 m");
  AUV_RECON_CHECK_OPTION(min_images >= 3, min_images, "must be >= 3 (a similarity has 7 dof)");
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  double m = values[mid];
  if (values.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(values.begin(), values.begin() + mid));
  }
  return m;
}

AlignmentResult alignToTruth(const std::vector<PosePair>& pairs, const AlignmentOptions& options) {
  options.check();
  AlignmentResult result;
  const size_t n = pairs.size();
  result.inliers.assign(n, false);
  if (n < options.min_images) {
    result.status = AlignmentStatus::TOO_FEW_IMAGES;
    result.message =
        std::to_string(n) + " images with ground truth, need " + std::to_string(options.min_images);
    return result;
  }
  std::mt19937_64 rng(options.seed);
  double scale = initialScale(pairs, rng, options.max_trials);
  if (!(scale > 0)) {
    result.status = AlignmentStatus::DEGENERATE;
    result.message = "all camera centres coincide (in the reconstruction or the truth)";
    return result;
  }

  // Least median of squares over minimal samples: two images with axis points (6 points),
  // three with centres only.
  const bool axes = options.axis_length_m > 0;
  const size_t sample_size = axes ? 2 : 3;
  std::vector<ImagePoints> points;
  auto build = [&](double s) {
    points.clear();
    for (const PosePair& pair : pairs)
      points.push_back(imagePoints(pair, options.axis_length_m, s));
  };
  build(scale);
  std::vector<std::vector<size_t>> samples;
  if (sample_size == 2 && n * (n - 1) / 2 <= static_cast<size_t>(options.max_trials)) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) samples.push_back({i, j});
  } else {
    std::vector<size_t> all(n);
    std::iota(all.begin(), all.end(), 0);
    for (int t = 0; t < options.max_trials; ++t) {
      std::vector<size_t> sample;
      std::sample(all.begin(), all.end(), std::back_inserter(sample), sample_size, rng);
      samples.push_back(sample);
    }
  }
  double best_median = std::numeric_limits<double>::infinity();
  Similarity best;
  std::vector<double> residuals(n);
  for (const auto& sample : samples) {
    Similarity candidate;
    if (!fit(points, sample, candidate)) continue;
    for (size_t i = 0; i < n; ++i) residuals[i] = residual(points[i], candidate);
    const double m = median(residuals);
    if (m < best_median) {
      best_median = m;
      best = candidate;
    }
  }
  if (!std::isfinite(best_median)) {
    result.status = AlignmentStatus::DEGENERATE;
    result.message = axes ? "camera poses do not fix a similarity"
                          : "camera centres are collinear: the rotation about their line is "
                            "undetermined (use axis points, axis_length_m > 0)";
    return result;
  }

  // Robust scale (Rousseeuw & Leroy, eq. 1.3 of chapter 5), inliers, refit; twice, the second
  // time with the axis points rebuilt at the fitted scale.
  Similarity current = best;
  double median_residual = best_median;
  for (int round = 0; round < 3; ++round) {
    const double sigma = 1.4826 *
                         (1.0 + 5.0 / std::max<double>(1.0, static_cast<double>(n) - sample_size)) *
                         median_residual;
    const double threshold = std::max(options.inlier_sigmas * sigma, options.min_inlier_m);
    std::vector<size_t> inliers;
    for (size_t i = 0; i < n; ++i) {
      residuals[i] = residual(points[i], current);
      if (residuals[i] <= threshold) inliers.push_back(i);
    }
    Similarity refit;
    if (inliers.size() < sample_size || !fit(points, inliers, refit)) break;
    current = refit;
    result.robust_sigma_m = sigma;
    if (axes) build(current.scale);
    for (size_t i = 0; i < n; ++i) residuals[i] = residual(points[i], current);
    median_residual = median(residuals);
  }
  const double sigma = 1.4826 *
                       (1.0 + 5.0 / std::max<double>(1.0, static_cast<double>(n) - sample_size)) *
                       median_residual;
  const double threshold = std::max(options.inlier_sigmas * sigma, options.min_inlier_m);
  result.robust_sigma_m = sigma;
  for (size_t i = 0; i < n; ++i) {
    result.inliers[i] = residual(points[i], current) <= threshold;
    result.num_inliers += result.inliers[i] ? 1 : 0;
  }
  result.similarity = current;
  if (result.num_inliers < options.min_images) {
    result.status = AlignmentStatus::TOO_FEW_IMAGES;
    std::ostringstream message;
    message << "only " << result.num_inliers << " of " << n
            << " images agree with one similarity (robust sigma " << sigma << " m)";
    result.message = message.str();
    return result;
  }
  result.status = AlignmentStatus::SUCCESS;
  return result;
}

PoseErrors poseErrors(const std::vector<PosePair>& pairs, const Similarity& similarity) {
  PoseErrors e;
  double sum = 0, sum_sq = 0, sum_rot = 0;
  for (const PosePair& pair : pairs) {
    const double d = (similarity.apply(pair.center_estimate) - pair.center_truth).norm();
    const Eigen::Matrix3d aligned = similarity.applyToCameraRotation(pair.rotation_estimate_cw);
    const double angle =
        Eigen::AngleAxisd(pair.rotation_truth_cw * aligned.transpose()).angle() * 180.0 / M_PI;
    e.position_m.push_back(d);
    e.rotation_deg.push_back(angle);
    sum += d;
    sum_sq += d * d;
    sum_rot += angle;
    e.max_position_m = std::max(e.max_position_m, d);
    e.max_rotation_deg = std::max(e.max_rotation_deg, angle);
  }
  if (!pairs.empty()) {
    const double n = static_cast<double>(pairs.size());
    e.mean_position_m = sum / n;
    e.rms_position_m = std::sqrt(sum_sq / n);
    e.mean_rotation_deg = sum_rot / n;
    e.median_position_m = median(e.position_m);
    e.median_rotation_deg = median(e.rotation_deg);
  }
  return e;
}

}  // namespace auv::recon::evaluate
