#include "auv/recon/color/correction.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "auv/recon/color/lalphabeta.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::color {

namespace {
const float kSqrt3 = std::sqrt(3.f);

/// Value at quantile `q` of `values` (partially reorders it).
float quantile(std::vector<float>& values, double q) {
  const size_t k =
      std::min(values.size() - 1, static_cast<size_t>(std::floor(q * (values.size() - 1) + 0.5)));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}
}  // namespace

void ColorOptions::check() const {
  AUV_RECON_CHECK_OPTION(chroma_strength >= 0 && chroma_strength <= 1, chroma_strength,
                         "must be in [0, 1]");
  AUV_RECON_CHECK_OPTION(cutoff_low >= 0 && cutoff_low < 0.5, cutoff_low,
                         "must be in [0, 0.5) (fraction of the pixels)");
  AUV_RECON_CHECK_OPTION(cutoff_high >= 0 && cutoff_high < 0.5, cutoff_high,
                         "must be in [0, 0.5) (fraction of the pixels)");
  AUV_RECON_CHECK_OPTION(cutoff_low + cutoff_high < 0.9, cutoff_low,
                         "cutoff_low + cutoff_high must be < 0.9");
  AUV_RECON_CHECK_OPTION(max_samples == 0 || max_samples >= 1000, max_samples,
                         "must be 0 (all pixels) or >= 1000");
}

CorrectedImage correctColor(const cv::Mat& bgr, const ColorOptions& options) {
  options.check();
  if (bgr.type() != CV_8UC3 || bgr.empty()) {
    throw std::invalid_argument("correctColor: expected a non-empty 8-bit 3-channel BGR image");
  }
  cv::Mat lab = bgrToLalphabeta(bgr);

  // Statistics on an even grid of pixels (a 12 Mpx frame needs no more for a mean/quantile).
  const size_t total = lab.total();
  const size_t step =
      options.max_samples > 0 ? std::max<size_t>(1, total / options.max_samples) : 1;
  std::vector<float> luminance;
  luminance.reserve(total / step + 1);
  const cv::Vec3f* data = lab.ptr<cv::Vec3f>(0);  // continuous: just created
  for (size_t i = 0; i < total; i += step) luminance.push_back(data[i][0]);
  std::vector<float> sorted = luminance;
  const float l_low = quantile(sorted, options.cutoff_low);
  const float l_high = quantile(sorted, 1.0 - options.cutoff_high);

  // The cast: chromatic means over the pixels inside the cut-off range (clipped and
  // near-black pixels have unreliable chroma: their logarithms are dominated by noise).
  double sum_alpha = 0, sum_beta = 0;
  size_t count = 0;
  for (size_t i = 0, k = 0; i < total; i += step, ++k) {
    if (luminance[k] < l_low || luminance[k] > l_high) continue;
    sum_alpha += data[i][1];
    sum_beta += data[i][2];
    ++count;
  }
  CorrectedImage result;
  ColorStatistics& stats = result.statistics;
  if (count > 0) {
    stats.mean_alpha = sum_alpha / count;
    stats.mean_beta = sum_beta / count;
  }
  stats.luminance_low = std::pow(10.0, l_low / kSqrt3);
  stats.luminance_high = std::pow(10.0, l_high / kSqrt3);
  const float shift_alpha = static_cast<float>(options.chroma_strength * stats.mean_alpha);
  const float shift_beta = static_cast<float>(options.chroma_strength * stats.mean_beta);

  const float y_low = static_cast<float>(stats.luminance_low);
  const float y_high = static_cast<float>(stats.luminance_high);
  // A flat image (or one cut entirely) has no range to stretch: leave its luminance alone.
  stats.stretched = options.stretch_luminance && y_high > y_low * 1.01f + 1e-6f;
  const float gain = stats.stretched ? 1.f / (y_high - y_low) : 1.f;
  const float floor_l = kSqrt3 * std::log10(kLinearFloor);

  cv::parallel_for_(cv::Range(0, lab.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      cv::Vec3f* p = lab.ptr<cv::Vec3f>(y);
      for (int x = 0; x < lab.cols; ++x) {
        p[x][1] -= shift_alpha;
        p[x][2] -= shift_beta;
        if (stats.stretched) {
          const float luminance_linear = std::pow(10.f, p[x][0] / kSqrt3);
          const float stretched = (luminance_linear - y_low) * gain;
          p[x][0] = stretched > kLinearFloor ? kSqrt3 * std::log10(stretched) : floor_l;
        }
      }
    }
  });
  result.image = lalphabetaToBgr(lab);
  return result;
}

}  // namespace auv::recon::color
