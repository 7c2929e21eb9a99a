#include "auv/recon/dense/matcher.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::dense {

void MatcherOptions::check() const {
  AUV_RECON_CHECK_OPTION(pyramid_levels >= 1 && pyramid_levels <= 8, pyramid_levels,
                         "must be in [1, 8]");
  AUV_RECON_CHECK_OPTION(min_level_size >= 16, min_level_size, "must be >= 16 px");
  AUV_RECON_CHECK_OPTION(window_radius >= 1 && window_radius <= 10, window_radius,
                         "must be in [1, 10] px");
  AUV_RECON_CHECK_OPTION(best_k >= 1, best_k, "must be >= 1");
  AUV_RECON_CHECK_OPTION(label_px > 0 && label_px <= 8, label_px, "must be in (0, 8] px");
  AUV_RECON_CHECK_OPTION(max_labels >= 8 && max_labels <= 2048, max_labels, "must be in [8, 2048]");
  AUV_RECON_CHECK_OPTION(search_labels >= 3 && search_labels <= 256, search_labels,
                         "must be in [3, 256]");
  AUV_RECON_CHECK_OPTION(range_margin >= 0 && range_margin < search_labels, range_margin,
                         "must be in [0, search_labels)");
  AUV_RECON_CHECK_OPTION(p1 >= 0, p1, "must be >= 0");
  AUV_RECON_CHECK_OPTION(p2 > p1 && p2 <= 7000, p2, "must be in (p1, 7000]");
  AUV_RECON_CHECK_OPTION(p2_edge_grey > 0, p2_edge_grey, "must be > 0");
  AUV_RECON_CHECK_OPTION(directions == 4 || directions == 8, directions, "must be 4 or 8");
  AUV_RECON_CHECK_OPTION(min_ncc > -1 && min_ncc < 1, min_ncc, "must be in (-1, 1)");
  AUV_RECON_CHECK_OPTION(uniqueness >= 0 && uniqueness < 1, uniqueness, "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(min_texture_grey >= 0, min_texture_grey, "must be >= 0");
  AUV_RECON_CHECK_OPTION(speckle_size >= 0, speckle_size, "must be >= 0 px");
  AUV_RECON_CHECK_OPTION(speckle_labels >= 1, speckle_labels, "must be >= 1");
  AUV_RECON_CHECK_OPTION(strip_rows >= 1 && strip_rows <= 4096, strip_rows, "must be in [1, 4096]");
}

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Labels of one level: inverse depths inv_min + label * step, label in [0, labels).
struct LabelGrid {
  double inv_min = 0, step = 1;
  int labels = 0;
  double inverseDepth(double label) const { return inv_min + label * step; }
  double label(double inverse_depth) const { return (inverse_depth - inv_min) / step; }
};

/// Pixel of the neighbour for master pixel p on the fronto-parallel plane of inverse depth
/// `inv`: p_n ~ A p + b inv, A = K_n R_rel K_m^-1, b = K_n t_rel.
struct PlaneSweep {
  Eigen::Matrix3d A;
  Eigen::Vector3d b;
  Eigen::Matrix3d homography(double inverse_depth) const {
    Eigen::Matrix3d h = A;
    h.col(2) += b * inverse_depth;
    return h;
  }
};

PlaneSweep planeSweep(const View& master, const View& neighbour) {
  const Eigen::Matrix3d r_rel = neighbour.R * master.R.transpose();
  const Eigen::Vector3d t_rel = neighbour.t - r_rel * master.t;
  return {neighbour.K * r_rel * master.K.inverse(), neighbour.K * t_rel};
}

/// Global labels of a level: the largest epipolar displacement between the nearest and the
/// farthest depth over a 3x3 grid of master pixels and all neighbours, in label_px steps.
int labelCount(const View& master, const std::vector<PlaneSweep>& sweeps, double inv_min,
               double inv_max, double label_px, int max_labels) {
  double displacement = 0;
  for (const PlaneSweep& sweep : sweeps) {
    for (double fy : {0.1, 0.5, 0.9}) {
      for (double fx : {0.1, 0.5, 0.9}) {
        const Eigen::Vector3d p(fx * (master.width - 1), fy * (master.height - 1), 1.0);
        const Eigen::Vector3d near = sweep.A * p + sweep.b * inv_max;
        const Eigen::Vector3d far = sweep.A * p + sweep.b * inv_min;
        if (near.z() <= 0 || far.z() <= 0) continue;
        displacement = std::max(displacement, (near.hnormalized() - far.hnormalized()).norm());
      }
    }
  }
  const int labels = static_cast<int>(std::ceil(displacement / label_px)) + 1;
  return std::clamp(labels, 4, max_labels);
}

/// Box mean and standard deviation of the master over the NCC window (replicated borders).
struct WindowStats {
  cv::Mat padded;  ///< the master with r px of replicated border
  cv::Mat mean, stddev;
};

WindowStats windowStats(const cv::Mat& grey, int r) {
  WindowStats stats;
  cv::copyMakeBorder(grey, stats.padded, r, r, r, r, cv::BORDER_REPLICATE);
  cv::Mat mean, mean_sq, squared;
  const cv::Size window(2 * r + 1, 2 * r + 1);
  cv::boxFilter(stats.padded, mean, CV_32F, window);
  cv::multiply(stats.padded, stats.padded, squared);
  cv::boxFilter(squared, mean_sq, CV_32F, window);
  const cv::Rect inner(r, r, grey.cols, grey.rows);
  stats.mean = mean(inner).clone();
  cv::Mat variance = mean_sq(inner) - stats.mean.mul(stats.mean);
  cv::max(variance, 0.0, variance);
  cv::sqrt(variance, stats.stddev);
  return stats;
}

struct LevelInput {
  const View* master;
  std::vector<View> neighbours;  ///< at this level
  std::vector<PlaneSweep> sweeps;
  WindowStats stats;
  LabelGrid grid;
};

/// Fills the costs of every pixel's interval. Hypothesis i of pixel q is the plane of label
/// low(q) + i: for each i and neighbour, the neighbour is resampled (cv::remap) at every
/// master pixel's hypothesis i, and the NCC of each master window with it comes from box
/// filters. Where low() is constant this is the fronto-parallel plane sweep; on a surface the
/// coarser level found, the window follows that surface (a staircase of one label at most)
/// instead of a fronto-parallel plane. Rows are processed in strips (parallel, bounded memory).
void computeCosts(const LevelInput& in, const MatcherOptions& options, LabelVolume& volume) {
  const int r = options.window_radius;
  const int w = volume.width, h = volume.height;
  const int strip = options.strip_rows;
  const int strips = (h + strip - 1) / strip;
  const size_t n_neighbours = in.neighbours.size();
  const float min_std = static_cast<float>(options.min_texture_grey);
  const cv::Size window(2 * r + 1, 2 * r + 1);
  const int best_k = options.best_k;
  const int last_label = in.grid.labels - 1;
  int offsets = 0;
  for (const uint16_t count : volume.count) offsets = std::max<int>(offsets, count);

#pragma omp parallel for schedule(dynamic)
  for (int s = 0; s < strips; ++s) {
    const int y0 = s * strip, sh = std::min(strip, h - y0);
    // The strip with r px of border on every side (replicated at the image's edges).
    const cv::Size extended(w + 2 * r, sh + 2 * r);
    const cv::Mat master_strip = in.stats.padded(cv::Rect(0, y0, extended.width, extended.height));
    cv::Mat map_x(extended, CV_32F), map_y(extended, CV_32F);
    cv::Mat warped, product, box_w, box_ww, box_mw;
    std::vector<float> ncc(n_neighbours * static_cast<size_t>(w) * sh);
    std::vector<float> scores(n_neighbours);
    for (int i = 0; i < offsets; ++i) {
      for (size_t k = 0; k < n_neighbours; ++k) {
        const View& neighbour = in.neighbours[k];
        const PlaneSweep& sweep = in.sweeps[k];
        const float max_x = static_cast<float>(neighbour.width - 1);
        const float max_y = static_cast<float>(neighbour.height - 1);
        for (int ye = 0; ye < extended.height; ++ye) {
          const int y = std::clamp(y0 + ye - r, 0, h - 1);
          float* mx = map_x.ptr<float>(ye);
          float* my = map_y.ptr<float>(ye);
          for (int xe = 0; xe < extended.width; ++xe) {
            const int x = std::clamp(xe - r, 0, w - 1);
            const size_t q = static_cast<size_t>(y) * w + x;
            const int label = std::min(volume.low[q] + i, last_label);
            const Eigen::Vector3d p =
                sweep.A * Eigen::Vector3d(x, y, 1.0) + sweep.b * in.grid.inverseDepth(label);
            if (p.z() <= 0) {
              mx[xe] = my[xe] = -1e6f;  // behind the neighbour: border value, marked below
              continue;
            }
            mx[xe] = static_cast<float>(p.x() / p.z());
            my[xe] = static_cast<float>(p.y() / p.z());
          }
        }
        cv::remap(neighbour.grey, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
        cv::boxFilter(warped, box_w, CV_32F, window);
        cv::multiply(warped, warped, product);
        cv::boxFilter(product, box_ww, CV_32F, window);
        cv::multiply(master_strip, warped, product);
        cv::boxFilter(product, box_mw, CV_32F, window);
        float* out = ncc.data() + k * static_cast<size_t>(w) * sh;
        for (int v = 0; v < sh; ++v) {
          const float* mean_m = in.stats.mean.ptr<float>(y0 + v);
          const float* std_m = in.stats.stddev.ptr<float>(y0 + v);
          const float* mx = map_x.ptr<float>(v + r) + r;
          const float* my = map_y.ptr<float>(v + r) + r;
          const float* bw = box_w.ptr<float>(v + r) + r;
          const float* bww = box_ww.ptr<float>(v + r) + r;
          const float* bmw = box_mw.ptr<float>(v + r) + r;
          for (int u = 0; u < w; ++u) {
            float value = std::numeric_limits<float>::quiet_NaN();
            const float var_w = bww[u] - bw[u] * bw[u];
            if (mx[u] >= 0 && my[u] >= 0 && mx[u] <= max_x && my[u] <= max_y &&
                var_w > min_std * min_std && std_m[u] > 0) {
              value = (bmw[u] - mean_m[u] * bw[u]) / (std_m[u] * std::sqrt(var_w));
            }
            out[static_cast<size_t>(v) * w + u] = value;
          }
        }
      }
      for (int v = 0; v < sh; ++v) {
        const float* std_m = in.stats.stddev.ptr<float>(y0 + v);
        for (int u = 0; u < w; ++u) {
          const size_t p = static_cast<size_t>(y0 + v) * w + u;
          if (i >= volume.count[p]) continue;
          uint16_t& cost = volume.costs(p)[i];
          if (std_m[u] < min_std) {
            cost = kCostScale;  // no texture: no evidence either way, SGM fills it in
            continue;
          }
          size_t valid = 0;
          for (size_t k = 0; k < n_neighbours; ++k) {
            const float value =
                ncc[k * static_cast<size_t>(w) * sh + static_cast<size_t>(v) * w + u];
            if (!std::isnan(value)) scores[valid++] = value;
          }
          if (valid == 0) {
            cost = kMaxCost;
            continue;
          }
          const size_t used = std::min(valid, static_cast<size_t>(best_k));
          std::partial_sort(scores.begin(), scores.begin() + used, scores.begin() + valid,
                            std::greater<float>());
          float mean = 0;
          for (size_t j = 0; j < used; ++j) mean += scores[j];
          mean /= used;
          cost = static_cast<uint16_t>(
              std::clamp(static_cast<int>(std::lround((1.0f - mean) * kCostScale)), 0, kMaxCost));
        }
      }
    }
  }
}

/// Per-pixel result of a level: inverse depth (0: none) and aggregated NCC.
struct LevelResult {
  cv::Mat inverse_depth, ncc;
};

LevelResult winnerTakesAll(const LevelInput& in, const LabelVolume& volume,
                           const std::vector<uint16_t>& sums, const MatcherOptions& options,
                           bool finest) {
  LevelResult result;
  result.inverse_depth = cv::Mat(volume.height, volume.width, CV_32F, cv::Scalar(0));
  result.ncc = cv::Mat(volume.height, volume.width, CV_32F, cv::Scalar(0));
  const float min_std = static_cast<float>(options.min_texture_grey);
  for (int y = 0; y < volume.height; ++y) {
    for (int x = 0; x < volume.width; ++x) {
      const size_t p = static_cast<size_t>(y) * volume.width + x;
      const int count = volume.count[p];
      if (count == 0 || in.stats.stddev.at<float>(y, x) < min_std) continue;
      const uint16_t* s = sums.data() + p * volume.stride;
      int best = 0;
      for (int i = 1; i < count; ++i) {
        if (s[i] < s[best]) best = i;
      }
      int second = std::numeric_limits<int>::max();
      for (int i = 0; i < count; ++i) {
        if (std::abs(i - best) > 1) second = std::min(second, static_cast<int>(s[i]));
      }
      const double ncc = 1.0 - static_cast<double>(volume.costs(p)[best]) / kCostScale;
      double offset = 0;
      if (best > 0 && best < count - 1) {
        const double denominator = s[best - 1] + s[best + 1] - 2.0 * s[best];
        if (denominator > 0) offset = 0.5 * (s[best - 1] - s[best + 1]) / denominator;
      }
      const double label = volume.low[p] + best + offset;
      if (finest) {
        if (ncc < options.min_ncc) continue;
        if (second != std::numeric_limits<int>::max() &&
            s[best] > (1.0 - options.uniqueness) * second) {
          continue;
        }
        // The minimum at the edge of a restricted interval lies probably outside it.
        if (best == 0 && volume.low[p] > 0) continue;
        if (best == count - 1 && volume.low[p] + count < in.grid.labels) continue;
      } else if (ncc <= 0) {
        continue;
      }
      result.inverse_depth.at<float>(y, x) = static_cast<float>(in.grid.inverseDepth(label));
      result.ncc.at<float>(y, x) = static_cast<float>(ncc);
    }
  }
  return result;
}

/// The intervals of a finer level from the coarser level's inverse depths: `stride` labels
/// centred on the coarse estimate (bilinearly upsampled, so that neighbouring intervals
/// follow the surface smoothly) and shifted, when it fits, to cover every label between the
/// minimum and the maximum of the 3x3 coarse neighbourhood widened by the margin; where the
/// neighbourhood spans more (a depth discontinuity) the interval stays on the pixel's own
/// estimate.
void rangesFromCoarse(const LevelResult& coarse, const LabelGrid& grid,
                      const MatcherOptions& options, LabelVolume& volume) {
  constexpr float kNone = 1e30f;
  const cv::Mat valid = coarse.inverse_depth > 0;
  cv::Mat low_source(coarse.inverse_depth.size(), CV_32F, cv::Scalar(kNone));
  cv::Mat high_source(coarse.inverse_depth.size(), CV_32F, cv::Scalar(-kNone));
  coarse.inverse_depth.copyTo(low_source, valid);
  coarse.inverse_depth.copyTo(high_source, valid);
  cv::Mat low, high;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::erode(low_source, low, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
  cv::dilate(high_source, high, kernel, {-1, -1}, 1, cv::BORDER_REPLICATE);
  // Own estimate, holes filled with the middle of their neighbourhood.
  cv::Mat filled = coarse.inverse_depth.clone();
  for (int y = 0; y < filled.rows; ++y) {
    for (int x = 0; x < filled.cols; ++x) {
      float& f = filled.at<float>(y, x);
      if (f <= 0 && low.at<float>(y, x) < kNone / 2) {
        f = 0.5f * (low.at<float>(y, x) + high.at<float>(y, x));
      }
    }
  }
  cv::Mat filled_mask;
  cv::Mat(filled > 0).convertTo(filled_mask, CV_32F, 1.0 / 255);
  const cv::Size size(volume.width, volume.height);
  cv::Mat centre_linear, centre_nearest, weight;
  cv::resize(filled, centre_linear, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(filled_mask, weight, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(filled, centre_nearest, size, 0, 0, cv::INTER_NEAREST);
  cv::resize(low, low, size, 0, 0, cv::INTER_NEAREST);
  cv::resize(high, high, size, 0, 0, cv::INTER_NEAREST);
  const int stride = volume.stride, labels = grid.labels;
  for (int y = 0; y < volume.height; ++y) {
    for (int x = 0; x < volume.width; ++x) {
      const size_t p = static_cast<size_t>(y) * volume.width + x;
      const float lo_inv = low.at<float>(y, x), hi_inv = high.at<float>(y, x);
      if (lo_inv >= kNone / 2) continue;  // nothing found around: not matched
      const float centre_inv = weight.at<float>(y, x) > 0.999f ? centre_linear.at<float>(y, x)
                                                               : centre_nearest.at<float>(y, x);
      if (centre_inv <= 0) continue;
      int first = static_cast<int>(std::lround(grid.label(centre_inv))) - stride / 2;
      const int need_first =
          static_cast<int>(std::floor(grid.label(lo_inv))) - options.range_margin;
      const int need_last = static_cast<int>(std::ceil(grid.label(hi_inv))) + options.range_margin;
      if (need_last - need_first + 1 <= stride) {
        first = std::clamp(first, need_last - stride + 1, need_first);
      }
      first = std::clamp(first, 0, std::max(0, labels - stride));
      volume.low[p] = first;
      volume.count[p] = static_cast<uint16_t>(std::min(stride, labels - first));
    }
  }
  // Unmatched pixels still lend their window samples to their neighbours' NCC: give them the
  // range start of the nearest matched pixel on their row (or the row above).
  for (int y = 0; y < volume.height; ++y) {
    int32_t last_low = -1;
    for (int x = 0; x < volume.width; ++x) {
      const size_t p = static_cast<size_t>(y) * volume.width + x;
      if (volume.count[p] > 0)
        last_low = volume.low[p];
      else if (last_low >= 0)
        volume.low[p] = last_low;
      else if (y > 0)
        volume.low[p] = volume.low[p - volume.width];
    }
  }
}

/// Removes blobs smaller than speckle_size whose labels differ by less than speckle_labels
/// (OpenCV's filterSpeckles on the labels in fixed point).
void removeSpeckles(cv::Mat& inverse_depth, const LabelGrid& grid, const MatcherOptions& options) {
  if (options.speckle_size == 0) return;
  constexpr int16_t kInvalid = std::numeric_limits<int16_t>::min();
  const double scale = std::min(16.0, 30000.0 / grid.labels);
  cv::Mat labels(inverse_depth.size(), CV_16S, cv::Scalar(kInvalid));
  for (int y = 0; y < inverse_depth.rows; ++y) {
    for (int x = 0; x < inverse_depth.cols; ++x) {
      const float inv = inverse_depth.at<float>(y, x);
      if (inv > 0) {
        labels.at<int16_t>(y, x) = static_cast<int16_t>(std::lround(grid.label(inv) * scale));
      }
    }
  }
  cv::filterSpeckles(labels, kInvalid, options.speckle_size,
                     std::max(1.0, options.speckle_labels * scale));
  inverse_depth.setTo(0, labels == kInvalid);
}

}  // namespace

DepthMapResult computeDepthMap(const View& master, const std::vector<View>& neighbours,
                               double depth_min, double depth_max, const MatcherOptions& options) {
  options.check();
  if (!(depth_min > 0) || !(depth_max > depth_min) || !std::isfinite(depth_max)) {
    throw std::invalid_argument("dense: image " + master.name + ": bad depth range [" +
                                std::to_string(depth_min) + ", " + std::to_string(depth_max) + "]");
  }
  if (neighbours.empty()) {
    throw std::invalid_argument("dense: image " + master.name + ": no neighbour to match");
  }
  if (master.grey.empty())
    throw std::invalid_argument("dense: image " + master.name + ": not loaded");
  for (const View& neighbour : neighbours) {
    if (neighbour.grey.empty()) {
      throw std::invalid_argument("dense: image " + neighbour.name + ": not loaded");
    }
  }
  const double inv_min = 1.0 / depth_max, inv_max = 1.0 / depth_min;
  int levels = options.pyramid_levels;
  while (levels > 1 && std::max(master.width, master.height) / std::pow(2.0, levels - 1) <
                           options.min_level_size) {
    --levels;
  }

  DepthMapResult result;
  LevelResult coarse;
  LabelGrid coarse_grid;
  const SgmPenalties penalties{options.p1, options.p2, options.p2_edge_grey, options.directions};
  for (int level = levels - 1; level >= 0; --level) {
    const double factor = std::pow(0.5, level);
    const auto levelSize = [&](const View& view) {
      return cv::Size(std::max(1, static_cast<int>(std::lround(view.width * factor))),
                      std::max(1, static_cast<int>(std::lround(view.height * factor))));
    };
    const cv::Size size = levelSize(master);
    const View master_level = level == 0 ? master : master.scaled(size.width, size.height);
    LevelInput in;
    in.master = &master_level;
    for (const View& neighbour : neighbours) {
      const cv::Size n_size = levelSize(neighbour);
      in.neighbours.push_back(level == 0 ? neighbour
                                         : neighbour.scaled(n_size.width, n_size.height));
      in.sweeps.push_back(planeSweep(master_level, in.neighbours.back()));
    }
    in.grid.labels = labelCount(master_level, in.sweeps, inv_min, inv_max, options.label_px,
                                level == levels - 1 ? options.max_labels : 1 << 15);
    in.grid.inv_min = inv_min;
    in.grid.step = (inv_max - inv_min) / (in.grid.labels - 1);
    in.stats = windowStats(master_level.grey, options.window_radius);

    LabelVolume volume;
    const auto start_cost = Clock::now();
    if (level == levels - 1) {
      volume.reset(size.width, size.height, in.grid.labels);
      std::fill(volume.count.begin(), volume.count.end(), static_cast<uint16_t>(in.grid.labels));
    } else {
      volume.reset(size.width, size.height, std::min(options.search_labels, in.grid.labels));
      rangesFromCoarse(coarse, in.grid, options, volume);
    }
    computeCosts(in, options, volume);
    for (uint16_t count : volume.count) result.hypotheses += count;
    result.seconds_cost += secondsSince(start_cost);

    const auto start_sgm = Clock::now();
    const std::vector<uint16_t> sums = aggregatePaths(volume, master_level.grey, penalties);
    coarse = winnerTakesAll(in, volume, sums, options, level == 0);
    result.seconds_sgm += secondsSince(start_sgm);
    coarse_grid = in.grid;
    result.labels_per_level.push_back(in.grid.labels);
    result.level_sizes.push_back(size);
  }

  removeSpeckles(coarse.inverse_depth, coarse_grid, options);
  result.depth = cv::Mat(coarse.inverse_depth.size(), CV_32F, cv::Scalar(0));
  result.confidence = cv::Mat(coarse.inverse_depth.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < result.depth.rows; ++y) {
    for (int x = 0; x < result.depth.cols; ++x) {
      const float inv = coarse.inverse_depth.at<float>(y, x);
      if (inv <= 0) continue;
      result.depth.at<float>(y, x) = 1.0f / inv;
      result.confidence.at<float>(y, x) = coarse.ncc.at<float>(y, x);
      ++result.valid_pixels;
    }
  }
  return result;
}

}  // namespace auv::recon::dense
