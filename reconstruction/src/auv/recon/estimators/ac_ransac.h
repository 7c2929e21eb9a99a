#pragma once
// A-contrario RANSAC (AC-RANSAC, also called ORSA): a RANSAC whose inlier threshold is not given
// but chosen per model as the one that makes the model least likely to be explained by chance
// (paper section 3.4.1, the geometric filtering of OpenMVG).
//
// References:
//  [1] L. Moisan, B. Stival, "A probabilistic criterion to detect rigid point matches between
//      two images and estimate the fundamental matrix", IJCV 57(3), 2004.
//  [2] L. Moisan, P. Moulon, P. Monasse, "Automatic homographic registration of a pair of
//      images, with a contrario elimination of outliers", IPOL 2 (2012), section 2 (NFA).
//  [3] P. Moulon, P. Monasse, R. Marlet, "Adaptive structure from motion with a contrario
//      model estimation", ACCV 2012.
//
// The number of false alarms of a model M with its k best-fitting data among n, residual e_k
// of the k-th (ascending), minimal sample size s and N_out models per sample is ([2] eq. 5)
//
//   NFA(M, k) = N_out * (n - s) * C(n, k) * C(k, s) * alpha(e_k)^(k - s)
//
// where alpha(e) is the probability that a datum drawn at random (uniform in the image) has a
// residual <= e: alpha(e) = alpha0 * e^d (d = 1 for a distance to a line, 2 for a distance to a
// point). The model is "meaningful" when min_k NFA < 1 (log10 NFA < 0); the arg-min k gives the
// inliers and e_k the adaptive threshold. Everything is computed in log10.
//
// Sampling: uniform minimal samples; once a meaningful model exists the run stops early when
// the usual RANSAC bound says an all-inlier sample was drawn with `confidence`. A caller that
// needs at least `min_inliers` inliers (a pair with fewer is dropped) bounds the run further:
// a model with k >= min_inliers inliers among n is drawn with `confidence` within
// requiredIterations(min_inliers / n, s, confidence) uniform samples, so a run that has found
// none by then stops (the exit of a hopeless pair: most failing pairs have a few tens of
// putative matches, where this bound is a few hundred samples instead of max_iterations), and
// a model with fewer than min_inliers data within the threshold bound is not scored at all
// (no sort, no NFA: the cheap rejection of most models of a failing pair), nor is one whose
// best k is below min_inliers. Then a reserve
// of iterations samples from the best model's inliers only ([2] section 2.4, "optimised
// ORSA"). Finally the kernel may refine the model on its inliers (non-minimal fit); the refined
// model is kept only if its NFA is not worse.
//
// A kernel is a class with:
//
//   using Model = ...;                        // e.g. Eigen::Matrix3d
//   static constexpr int kMinimalSample;      // s
//   static constexpr int kMaxModels;          // N_out: most solutions of one minimal sample
//   size_t size() const;                      // n, number of data
//   void fit(const std::vector<int>& sample, std::vector<Model>* models) const;  // minimal
//   void residuals(const Model& m, std::vector<double>* r) const;  // r[i] >= 0 for all i,
//                                             // in px; +inf for a datum the model rejects
//   double logAlpha0() const;                 // log10 alpha0 (probability of residual <= 1)
//   double errorDimension() const;            // d in alpha(e) = alpha0 * e^d
//   bool refine(const std::vector<int>& inliers, Model* model) const;  // false: unchanged
//
// The kernels of this library: essential.h, fundamental.h, homography.h, absolute_pose.h.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace auv::recon::estimators {

struct AcRansacOptions {
  /// Most minimal samples drawn (the reserve of focused samples included).
  int max_iterations = 4096;
  /// Upper bound of the adaptive threshold, in the kernel's residual unit (px); infinity: none.
  double max_threshold = std::numeric_limits<double>::infinity();
  /// A model is accepted when log10(NFA) < this (0: NFA < 1, the a-contrario default).
  double max_log10_nfa = 0.0;
  /// Fraction of max_iterations kept to sample from the best model's inliers ([2] 2.4).
  double reserve_fraction = 0.1;
  /// Early stop: probability that an all-inlier sample was drawn (RANSAC bound on the best
  /// model's inlier ratio). 1 disables the early stop.
  double confidence = 0.99;
  /// Refine the best model on its inliers with the kernel's non-minimal fit.
  bool refine = true;
  /// Random generator seed (runs are deterministic for one seed).
  uint64_t seed = 42;
  /// Fewest inliers a useful model has. Models with fewer are not scored, and the run stops
  /// when none was found within the RANSAC bound for this count (see above): a success then
  /// has >= min_inliers inliers. 0: no such need (any k > s; the plain sample budget).
  int min_inliers = 0;

  /// Throws OptionError naming the field and its value.
  void check() const;
};

enum class AcRansacStatus {
  SUCCESS,              ///< a meaningful model (log10 NFA < max_log10_nfa)
  TOO_FEW_DATA,         ///< n <= minimal sample size
  NO_MEANINGFUL_MODEL,  ///< models were fitted but none was meaningful
};

std::string acRansacStatusName(AcRansacStatus status);

template <class Model>
struct AcRansacResult {
  AcRansacStatus status = AcRansacStatus::TOO_FEW_DATA;
  Model model{};             ///< the best model (meaningful only on SUCCESS)
  std::vector<int> inliers;  ///< indices of the inliers, ascending (empty unless SUCCESS)
  double log10_nfa = std::numeric_limits<double>::infinity();
  double threshold = 0;  ///< adaptive threshold found (largest inlier residual), px
  int iterations = 0;    ///< minimal samples drawn
  /// No meaningful model of min_inliers inliers within the (shorter) min_inliers bound.
  bool hopeless = false;
  bool refined = false;  ///< the kernel's refinement was kept

  bool success() const { return status == AcRansacStatus::SUCCESS; }
  size_t numInliers() const { return inliers.size(); }
};

namespace detail {

/// log10 C(n, k) for k = 0..n.
std::vector<double> log10CombinationsOfN(size_t n);
/// log10 C(k, s) for k = 0..n.
std::vector<double> log10CombinationsOfK(size_t s, size_t n);

/// Best (log10 NFA, k) over the sorted residuals (ascending; the smallest of the n data, it may
/// be a prefix), k > s, e_k <= max_threshold; log_c_n, log_c_k are the tables for all n data.
/// k = 0 when no k qualifies.
struct NfaPoint {
  double log10_nfa = std::numeric_limits<double>::infinity();
  size_t k = 0;
};
NfaPoint bestNfa(const std::vector<double>& sorted_residuals, size_t s, double log_alpha0,
                 double error_dimension, double log10_e0, double max_threshold,
                 const std::vector<double>& log_c_n, const std::vector<double>& log_c_k);

/// RANSAC bound: samples needed to draw one all-inlier minimal sample with `confidence`.
double requiredIterations(double inlier_ratio, int sample_size, double confidence);

}  // namespace detail

/// Runs AC-RANSAC with `kernel` (see the kernel contract above). Throws OptionError on bad
/// options; never throws for degenerate data (the status says it).
template <class Kernel>
AcRansacResult<typename Kernel::Model> acRansac(const Kernel& kernel,
                                                const AcRansacOptions& options = {}) {
  using Model = typename Kernel::Model;
  options.check();
  AcRansacResult<Model> result;
  const size_t n = kernel.size();
  const size_t s = static_cast<size_t>(Kernel::kMinimalSample);
  if (n <= s) return result;  // TOO_FEW_DATA
  result.status = AcRansacStatus::NO_MEANINGFUL_MODEL;

  const double log10_e0 = std::log10(static_cast<double>(Kernel::kMaxModels) * (n - s));
  const std::vector<double> log_c_n = detail::log10CombinationsOfN(n);
  const std::vector<double> log_c_k = detail::log10CombinationsOfK(s, n);
  const double log_alpha0 = kernel.logAlpha0();
  const double dimension = kernel.errorDimension();

  std::mt19937_64 random(options.seed);
  std::vector<int> pool(n);  // indices sampled from (all, then the best inliers)
  std::iota(pool.begin(), pool.end(), 0);
  std::vector<int> sample(s);
  std::vector<Model> models;
  std::vector<double> residuals, sorted;
  std::vector<std::pair<double, int>> ranked;

  // Residuals beyond the bound, or where alpha(e) >= 1 (a model can never be meaningful with
  // them), cannot be inliers: only the others are sorted.
  const double cutoff = std::min(options.max_threshold, std::pow(10.0, -log_alpha0 / dimension));
  const size_t min_k = std::max(s + 1, static_cast<size_t>(options.min_inliers));  // check(): >= 0

  // NFA of one model: fills ranked (residual, index) ascending and returns the best point.
  auto evaluate = [&](const Model& model) {
    kernel.residuals(model, &residuals);
    ranked.clear();
    for (size_t i = 0; i < n; ++i) {
      if (residuals[i] <= cutoff) ranked.emplace_back(residuals[i], static_cast<int>(i));
    }
    if (ranked.size() < min_k) return detail::NfaPoint{};  // too few within the bound
    std::sort(ranked.begin(), ranked.end());
    sorted.resize(ranked.size());
    for (size_t i = 0; i < ranked.size(); ++i) sorted[i] = ranked[i].first;
    // The model's own a-contrario inliers (its best k over all k) must reach min_k: a model is
    // not stretched to min_k at a looser threshold than its best.
    const detail::NfaPoint best =
        detail::bestNfa(sorted, s, log_alpha0, dimension, log10_e0, cutoff, log_c_n, log_c_k);
    return best.k >= min_k ? best : detail::NfaPoint{};
  };
  auto keep = [&](const Model& model, const detail::NfaPoint& best) {
    result.model = model;
    result.log10_nfa = best.log10_nfa;
    result.threshold = ranked[best.k - 1].first;
    result.inliers.resize(best.k);
    for (size_t i = 0; i < best.k; ++i) result.inliers[i] = ranked[i].second;
  };

  // One minimal sample without replacement from `from` (partial Fisher-Yates), its models
  // evaluated; true when one beat the best so far.
  auto iterate = [&](std::vector<int>& from) {
    for (size_t i = 0; i < s; ++i) {
      std::uniform_int_distribution<size_t> pick(i, from.size() - 1);
      std::swap(from[i], from[pick(random)]);
      sample[i] = from[i];
    }
    models.clear();
    kernel.fit(sample, &models);
    bool better = false;
    for (const Model& model : models) {
      const detail::NfaPoint best = evaluate(model);
      if (best.k > 0 && best.log10_nfa < result.log10_nfa) {
        keep(model, best);
        better = true;
      }
    }
    return better;
  };
  auto meaningful = [&] { return result.log10_nfa < options.max_log10_nfa; };

  const int reserve = static_cast<int>(options.max_iterations * options.reserve_fraction);
  int uniform_budget = options.max_iterations - reserve;
  // With a caller's min_inliers: no more samples than it takes to draw a model of min_k
  // inliers, if there is one (0 keeps the plain budget).
  bool bounded = false;
  if (options.min_inliers > 0) {
    const double enough = detail::requiredIterations(static_cast<double>(min_k) / n,
                                                     static_cast<int>(s), options.confidence);
    bounded = enough < uniform_budget;
    if (bounded) uniform_budget = std::max(1, static_cast<int>(std::ceil(enough)));
  }
  int iteration = 0;
  // Uniform phase, stopped early by the RANSAC bound on the best meaningful model's inliers.
  while (iteration < uniform_budget) {
    ++iteration;
    if (iterate(pool) && meaningful()) {
      const double ratio = static_cast<double>(result.inliers.size()) / n;
      const double needed =
          detail::requiredIterations(ratio, static_cast<int>(s), options.confidence);
      if (needed < uniform_budget) {
        uniform_budget = std::max(iteration, static_cast<int>(std::ceil(needed)));
      }
    }
  }
  // Focused phase ([2] 2.4): samples among the best model's inliers only.
  if (meaningful()) {
    pool = result.inliers;
    for (int extra = 0; extra < reserve && pool.size() >= s; ++extra) {
      ++iteration;
      if (iterate(pool)) pool = result.inliers;
    }
  }
  result.iterations = iteration;

  if (!(result.log10_nfa < options.max_log10_nfa)) {
    result.inliers.clear();
    result.hopeless = bounded;
    return result;  // NO_MEANINGFUL_MODEL
  }
  if (options.refine) {
    Model refined = result.model;
    if (kernel.refine(result.inliers, &refined)) {
      const detail::NfaPoint best = evaluate(refined);
      if (best.k > 0 && best.log10_nfa <= result.log10_nfa) {
        keep(refined, best);
        result.refined = true;
      }
    }
  }
  std::sort(result.inliers.begin(), result.inliers.end());
  result.status = AcRansacStatus::SUCCESS;
  return result;
}

}  // namespace auv::recon::estimators
