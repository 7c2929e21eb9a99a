#include "auv/recon/dense/sgm.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace auv::recon::dense {

void LabelVolume::reset(int width_, int height_, int stride_) {
  width = width_;
  height = height_;
  stride = stride_;
  low.assign(pixels(), 0);
  count.assign(pixels(), 0);
  cost.assign(pixels() * static_cast<size_t>(stride), static_cast<uint16_t>(kMaxCost));
}

namespace {

struct Direction {
  int dx, dy;  ///< offset of the previous pixel on the path, for the forward pass
};

/// One half of the aggregation: the forward pass (rows top to bottom, left to right) takes
/// the paths arriving from the left, upper-left, above and upper-right; the backward pass
/// mirrors them. Adds every path's L into `sums`.
void aggregatePass(const LabelVolume& volume, const cv::Mat& guide, const SgmPenalties& pen,
                   bool forward, std::vector<uint16_t>& sums) {
  const int w = volume.width, h = volume.height, stride = volume.stride;
  std::vector<Direction> directions = {{-1, 0}, {0, -1}};
  if (pen.directions == 8) {
    directions.push_back({-1, -1});
    directions.push_back({1, -1});
  }
  const int sign = forward ? 1 : -1;
  const size_t row_size = static_cast<size_t>(w) * stride;
  const size_t n_dir = directions.size();
  // L of the previous and the current row per direction, and their minima per pixel.
  std::vector<uint16_t> previous(n_dir * row_size), current(n_dir * row_size);
  std::vector<int> previous_min(n_dir * w), current_min(n_dir * w);
  std::vector<int> path(stride);

  for (int step_y = 0; step_y < h; ++step_y) {
    const int y = forward ? step_y : h - 1 - step_y;
    const float* guide_row = guide.ptr<float>(y);
    for (int step_x = 0; step_x < w; ++step_x) {
      const int x = forward ? step_x : w - 1 - step_x;
      const size_t p = static_cast<size_t>(y) * w + x;
      const int count_p = volume.count[p];
      const int low_p = volume.low[p];
      const uint16_t* cost_p = volume.costs(p);
      uint16_t* sum_p = sums.data() + p * stride;
      for (size_t d = 0; d < n_dir; ++d) {
        uint16_t* out = current.data() + d * row_size + static_cast<size_t>(x) * stride;
        int& out_min = current_min[d * w + x];
        if (count_p == 0) {
          out_min = -1;  // marks "no path through here"
          continue;
        }
        const int qx = x + sign * directions[d].dx, qy = y + sign * directions[d].dy;
        const bool same_row = directions[d].dy == 0;
        int count_q = 0, low_q = 0, min_q = 0;
        const uint16_t* path_q = nullptr;
        if (qx >= 0 && qx < w && qy >= 0 && qy < h) {
          const size_t q = static_cast<size_t>(qy) * w + qx;
          const int stored_min = same_row ? current_min[d * w + qx] : previous_min[d * w + qx];
          if (volume.count[q] > 0 && stored_min >= 0) {
            count_q = volume.count[q];
            low_q = volume.low[q];
            min_q = stored_min;
            path_q = (same_row ? current.data() : previous.data()) + d * row_size +
                     static_cast<size_t>(qx) * stride;
          }
        }
        int minimum = std::numeric_limits<int>::max();
        if (path_q == nullptr) {
          for (int i = 0; i < count_p; ++i) {
            path[i] = cost_p[i];
            minimum = std::min(minimum, path[i]);
          }
        } else {
          const float grey_q = guide.ptr<float>(qy)[qx];
          const double edge = std::abs(guide_row[x] - grey_q) / pen.p2_edge_grey;
          const int p2 = std::max(pen.p1 + 1, static_cast<int>(pen.p2 / (1.0 + edge)));
          const int jump = min_q + p2;
          for (int i = 0; i < count_p; ++i) {
            const int j = low_p + i - low_q;  // the same label in q's interval
            int best = jump;
            if (j >= 0 && j < count_q) best = std::min(best, static_cast<int>(path_q[j]));
            if (j - 1 >= 0 && j - 1 < count_q) best = std::min(best, path_q[j - 1] + pen.p1);
            if (j + 1 >= 0 && j + 1 < count_q) best = std::min(best, path_q[j + 1] + pen.p1);
            path[i] = cost_p[i] + best - min_q;
            minimum = std::min(minimum, path[i]);
          }
        }
        for (int i = 0; i < count_p; ++i) {
          out[i] = static_cast<uint16_t>(path[i]);
          sum_p[i] = static_cast<uint16_t>(sum_p[i] + path[i]);
        }
        out_min = minimum;
      }
    }
    std::swap(previous, current);
    std::swap(previous_min, current_min);
  }
}

}  // namespace

std::vector<uint16_t> aggregatePaths(const LabelVolume& volume, const cv::Mat& guide,
                                     const SgmPenalties& penalties) {
  CV_Assert(guide.type() == CV_32F && guide.cols == volume.width && guide.rows == volume.height);
  CV_Assert(penalties.directions == 4 || penalties.directions == 8);
  // Each path value is at most kMaxCost + P2 after the minimum is subtracted: the sums of 8
  // stay within uint16 as long as P2 <= 7000.
  CV_Assert(penalties.p2 <= 7000 && penalties.p1 >= 0);
  std::vector<uint16_t> forward(volume.cost.size(), 0), backward(volume.cost.size(), 0);
#pragma omp parallel sections
  {
#pragma omp section
    aggregatePass(volume, guide, penalties, true, forward);
#pragma omp section
    aggregatePass(volume, guide, penalties, false, backward);
  }
  for (size_t i = 0; i < forward.size(); ++i) {
    forward[i] = static_cast<uint16_t>(forward[i] + backward[i]);
  }
  return forward;
}

}  // namespace auv::recon::dense
