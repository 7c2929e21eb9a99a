#include "auv/recon/estimators/ac_ransac.h"

#include "auv/recon/common/stage_error.h"

namespace auv::recon::estimators {

void AcRansacOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_iterations > 0, max_iterations, "must be > 0");
  AUV_RECON_CHECK_OPTION(max_threshold > 0, max_threshold, "must be > 0 px (infinity: no bound)");
  AUV_RECON_CHECK_OPTION(std::isfinite(max_log10_nfa), max_log10_nfa, "must be finite");
  AUV_RECON_CHECK_OPTION(reserve_fraction >= 0 && reserve_fraction < 1, reserve_fraction,
                         "must be in [0, 1)");
  AUV_RECON_CHECK_OPTION(confidence > 0 && confidence <= 1, confidence, "must be in (0, 1]");
  AUV_RECON_CHECK_OPTION(min_inliers >= 0, min_inliers, "must be >= 0 (0: minimal sample + 1)");
}

std::string acRansacStatusName(AcRansacStatus status) {
  switch (status) {
    case AcRansacStatus::SUCCESS:
      return "SUCCESS";
    case AcRansacStatus::TOO_FEW_DATA:
      return "TOO_FEW_DATA";
    case AcRansacStatus::NO_MEANINGFUL_MODEL:
      return "NO_MEANINGFUL_MODEL";
  }
  return "UNKNOWN";
}

namespace detail {

std::vector<double> log10CombinationsOfN(size_t n) {
  // log10 C(n, k) = log10 C(n, k - 1) + log10((n - k + 1) / k).
  std::vector<double> table(n + 1, 0.0);
  for (size_t k = 1; k <= n; ++k) {
    table[k] = table[k - 1] + std::log10(static_cast<double>(n - k + 1) / static_cast<double>(k));
  }
  return table;
}

std::vector<double> log10CombinationsOfK(size_t s, size_t n) {
  // log10 C(k, s) = log10 C(k - 1, s) + log10(k / (k - s)) for k > s; C(s, s) = 1.
  std::vector<double> table(n + 1, 0.0);
  for (size_t k = s + 1; k <= n; ++k) {
    table[k] = table[k - 1] + std::log10(static_cast<double>(k) / static_cast<double>(k - s));
  }
  return table;
}

NfaPoint bestNfa(const std::vector<double>& sorted_residuals, size_t s, double log_alpha0,
                 double error_dimension, double log10_e0, double max_threshold,
                 const std::vector<double>& log_c_n, const std::vector<double>& log_c_k) {
  NfaPoint best;
  const size_t n = sorted_residuals.size();
  // Residuals below 1e-3 px count as 1e-3 px: keypoints are far coarser than that, and the
  // sample's own points (residual ~0) would otherwise dominate through log10(0).
  constexpr double kTiny = 1e-3;
  for (size_t k = s + 1; k <= n; ++k) {
    const double e = sorted_residuals[k - 1];
    if (!(e <= max_threshold)) break;  // also stops at +inf / NaN
    const double log_alpha = log_alpha0 + error_dimension * std::log10(std::max(e, kTiny));
    // The probability cannot exceed 1: a larger alpha means no information.
    const double nfa =
        log10_e0 + std::min(log_alpha, 0.0) * static_cast<double>(k - s) + log_c_n[k] + log_c_k[k];
    if (nfa < best.log10_nfa) {
      best.log10_nfa = nfa;
      best.k = k;
    }
  }
  return best;
}

double requiredIterations(double inlier_ratio, int sample_size, double confidence) {
  if (confidence >= 1.0) return std::numeric_limits<double>::infinity();
  const double all_inliers = std::pow(inlier_ratio, sample_size);
  if (all_inliers >= 1.0) return 1.0;
  if (all_inliers <= 0.0) return std::numeric_limits<double>::infinity();
  return std::log(1.0 - confidence) / std::log(1.0 - all_inliers);
}

}  // namespace detail
}  // namespace auv::recon::estimators
