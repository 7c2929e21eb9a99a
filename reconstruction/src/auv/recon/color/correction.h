#pragma once
// Underwater colour correction of Bianco et al. (paper section 3.2, reference [47]; the method
// is described in Bianco, Muzzupappa, Bruno, Garcia, Neumann 2015, "A new color correction
// method for underwater imaging"): in Ruderman's lαβ space (lalphabeta.h)
//
//   1. the chromatic components are shifted so that their distributions are centred on the
//      white point (α, β) = (0, 0) — the grey-world assumption in lαβ (uniform illumination):
//      α' = α − s·mean(α), β' = β − s·mean(β);
//   2. the luminance histogram is cut off at both ends and stretched to the full range.
//
// The stretch is linear in the linear-light luminance Y = 10^(l/√3) (the geometric mean of
// L, M, S): the cut-off quantiles Y_lo, Y_hi map to 0 and 1, so an additive veil (backscatter,
// roughly uniform) is removed and the contrast restored; l' = √3 log10(Y'), α and β (colour
// ratios) are kept. Pixels outside [Y_lo, Y_hi] are clipped (the cut-off).

#include <opencv2/core.hpp>

namespace auv::recon::color {

struct ColorOptions {
  /// Fraction of the chromatic shift applied: 1 = distributions centred on (0, 0) (the
  /// paper's correction), 0 = no colour cast removal.
  double chroma_strength = 1.0;
  /// Fraction of the pixels cut off at the dark end of the luminance histogram.
  double cutoff_low = 0.005;
  /// Fraction of the pixels cut off at the bright end.
  double cutoff_high = 0.005;
  /// Luminance histogram cut-off and stretch on/off.
  bool stretch_luminance = true;
  /// Statistics are taken on at most this many pixels (an even grid subsample; 0 = all).
  int max_samples = 500000;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

/// What a correction measured and changed (for report.json and the benchmark).
struct ColorStatistics {
  double mean_alpha = 0, mean_beta = 0;  ///< chromatic means before the shift (the cast)
  double luminance_low = 0;              ///< Y at the low cut-off (linear, 0..1)
  double luminance_high = 0;             ///< Y at the high cut-off
  bool stretched = false;                ///< false: flat luminance, nothing to stretch
};

struct CorrectedImage {
  cv::Mat image;  ///< 8-bit BGR
  ColorStatistics statistics;
};

/// Corrects one 8-bit BGR image. Throws std::invalid_argument for another image type.
CorrectedImage correctColor(const cv::Mat& bgr, const ColorOptions& options);

}  // namespace auv::recon::color
