#include "auv/recon/color/water_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include <ceres/ceres.h>
#include <yaml-cpp/yaml.h>
#include <Eigen/Eigenvalues>

#include "auv/config/yaml_section.h"
#include "auv/recon/color/lalphabeta.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"

namespace auv::recon::color {

namespace {

// V B(z) - I of one dark pixel of one channel; parameters (Binf, b, J', d') of the channel.
struct BackscatterResidual {
  BackscatterResidual(double range, double cos4, double value) : z(range), k(cos4), i(value) {}
  template <class T>
  bool operator()(const T* p, const T* v, T* residual) const {
    const T vignette = T(1) - v[0] * (T(1) - T(k));
    residual[0] =
        vignette * (p[0] * (T(1) - ceres::exp(-p[1] * T(z))) + p[2] * ceres::exp(-p[3] * T(z))) -
        T(i);
    return true;
  }
  double z, k, i;
};

// log D - (log J_p - beta z) of one channel of one observation.
struct AttenuationResidual {
  AttenuationResidual(int channel, double range, double log_signal)
      : c(channel), z(range), log_d(log_signal) {}
  template <class T>
  bool operator()(const T* log_j, const T* beta, T* residual) const {
    residual[0] = T(log_d) - (log_j[c] - beta[c] * T(z));
    return true;
  }
  int c;
  double z, log_d;
};

// I / V - (J_p exp(-beta z) + B(z)) of one channel of one observation, in linear light: the
// joint refinement of the attenuation and the backscatter (J' exp(-d' z) kept).
struct JointResidual {
  JointResidual(int channel, double range, double value, double residual_term)
      : c(channel), z(range), i(value), jd(residual_term) {}
  template <class T>
  bool operator()(const T* log_j, const T* beta, const T* bs, T* residual) const {
    const T direct = ceres::exp(log_j[c] - beta[c] * T(z));
    const T veil = bs[c] * (T(1) - ceres::exp(-bs[3 + c] * T(z))) + T(jd);
    residual[0] = T(i) - (direct + veil);
    return true;
  }
  int c;
  double z, i, jd;
};

// log J - (a + g . d) of one point and channel.
struct GradientResidual {
  GradientResidual(const Eigen::Vector3d& offset, double log_color) : d(offset), y(log_color) {}
  template <class T>
  bool operator()(const T* a, const T* g, T* residual) const {
    residual[0] = T(y) - (a[0] + g[0] * T(d.x()) + g[1] * T(d.y()) + g[2] * T(d.z()));
    return true;
  }
  Eigen::Vector3d d;
  double y;
};

double percentile(std::vector<float> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

const std::vector<float>& srgbTable() {  // linear [0, 1] in 2^16 steps -> sRGB [0, 255]
  static const std::vector<float> table = [] {
    std::vector<float> t(65537);
    for (size_t i = 0; i < t.size(); ++i) t[i] = 255.0f * linearToSrgb(i / 65536.0f);
    return t;
  }();
  return table;
}

Eigen::Array3d readTriple(const YAML::Node& root, const char* key,
                          const std::filesystem::path& file) {
  const YAML::Node node = root[key];
  if (!node || !node.IsSequence() || node.size() != 3) {
    throw std::runtime_error(file.string() + ": " + key + ": expected [r, g, b]");
  }
  Eigen::Array3d v;
  for (int c = 0; c < 3; ++c) v[c] = node[c].as<double>();
  if (!v.allFinite()) throw std::runtime_error(file.string() + ": " + key + ": not finite");
  return v;
}

}  // namespace

Eigen::Array3d WaterModel::backscatter(double range) const {
  return backscatter_infinity * (1.0 - (-backscatter_coefficient * range).exp()) +
         residual_signal * (-residual_decay * range).exp();
}

Eigen::Array3d WaterModel::illuminant(const Eigen::Vector3d& position) const {
  return (illuminant_gradient * (position - illuminant_origin)).array().exp();
}

void WaterFitOptions::check() const {
  AUV_RECON_CHECK_OPTION(range_bins >= 2 && range_bins <= 1000, range_bins, "must be in [2, 1000]");
  AUV_RECON_CHECK_OPTION(dark_fraction > 0 && dark_fraction <= 0.5, dark_fraction,
                         "must be in (0, 0.5]");
  AUV_RECON_CHECK_OPTION(min_signal > 0 && min_signal < 1, min_signal, "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(min_views >= 2, min_views, "must be >= 2");
  AUV_RECON_CHECK_OPTION(min_range_ratio >= 1, min_range_ratio, "must be >= 1");
  AUV_RECON_CHECK_OPTION(max_attenuation > 0, max_attenuation, "must be > 0");
  AUV_RECON_CHECK_OPTION(loss_scale > 0, loss_scale, "must be > 0");
  AUV_RECON_CHECK_OPTION(joint_loss_scale > 0, joint_loss_scale, "must be > 0");
  AUV_RECON_CHECK_OPTION(white_balance == "grey_world" || white_balance == "none", white_balance,
                         "must be grey_world or none");
  AUV_RECON_CHECK_OPTION(max_gain >= 1, max_gain, "must be >= 1");
  AUV_RECON_CHECK_OPTION(illuminant == "uniform" || illuminant == "gradient", illuminant,
                         "must be uniform or gradient");
}

BackscatterFitStats fitBackscatter(const std::vector<RangeSample>& samples,
                                   const WaterFitOptions& options, WaterModel& model) {
  BackscatterFitStats stats;
  stats.samples = samples.size();
  std::vector<float> ranges;
  ranges.reserve(samples.size());
  for (const RangeSample& s : samples) ranges.push_back(s.range);
  // Bins between the 1st and 99th percentile of the ranges (a few stray far pixels would
  // otherwise stretch the bins).
  const double lo = percentile(ranges, 0.01), hi = percentile(ranges, 0.99);
  if (!(hi > lo)) throw std::invalid_argument("backscatter fit: all samples at one range");
  std::vector<std::vector<const RangeSample*>> bins(options.range_bins);
  for (const RangeSample& s : samples) {
    if (s.range < lo || s.range > hi) continue;
    const int k = std::min(options.range_bins - 1,
                           static_cast<int>((s.range - lo) / (hi - lo) * options.range_bins));
    bins[k].push_back(&s);
  }
  std::vector<const RangeSample*> dark;
  for (auto& bin : bins) {
    const size_t n = static_cast<size_t>(std::ceil(options.dark_fraction * bin.size()));
    if (n == 0) continue;
    std::nth_element(
        bin.begin(), bin.begin() + (n - 1), bin.end(),
        [](const RangeSample* a, const RangeSample* b) { return a->rgb.sum() < b->rgb.sum(); });
    dark.insert(dark.end(), bin.begin(), bin.begin() + n);
  }
  stats.dark_samples = dark.size();
  if (dark.size() < 20) {
    throw std::invalid_argument("backscatter fit: " + std::to_string(dark.size()) +
                                " dark samples (at least 20 needed)");
  }
  const double median_range = percentile(ranges, 0.5);
  Eigen::Array3d max_value = Eigen::Array3d::Zero();
  for (const RangeSample* s : dark) max_value = max_value.max(s->rgb.cast<double>());
  double best_cost = std::numeric_limits<double>::infinity();
  // Several starts (Sea-thru restarts its curve fit too): the two exponentials trade off. One
  // problem for the three channels: they share the vignetting.
  for (double b_start : {0.3, 1.0, 3.0}) {
    for (double d_start : {0.3, 1.0, 3.0}) {
      std::array<Eigen::Vector4d, 3> p;
      for (int c = 0; c < 3; ++c) {
        p[c] = Eigen::Vector4d(std::max(1e-3, max_value[c]), b_start / median_range, 0,
                               d_start / median_range);
      }
      double v = options.estimate_vignetting ? 0.2 : model.vignetting;
      ceres::Problem problem;
      for (const RangeSample* s : dark) {
        for (int c = 0; c < 3; ++c) {
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BackscatterResidual, 1, 4, 1>(
                                       new BackscatterResidual(s->range, s->cos4, s->rgb[c])),
                                   nullptr, p[c].data(), &v);
        }
      }
      for (int c = 0; c < 3; ++c) {
        const double upper[4] = {1.0, options.max_attenuation, 1.0, options.max_attenuation};
        for (int i = 0; i < 4; ++i) {
          problem.SetParameterLowerBound(p[c].data(), i, 0.0);
          problem.SetParameterUpperBound(p[c].data(), i, upper[i]);
        }
      }
      problem.SetParameterLowerBound(&v, 0, 0.0);
      problem.SetParameterUpperBound(&v, 0, 0.9);
      if (!options.estimate_vignetting) problem.SetParameterBlockConstant(&v);
      ceres::Solver::Options solver;
      solver.max_num_iterations = 100;
      ceres::Solver::Summary summary;
      ceres::Solve(solver, &problem, &summary);
      if (!summary.IsSolutionUsable() || summary.final_cost >= best_cost) continue;
      best_cost = summary.final_cost;
      for (int c = 0; c < 3; ++c) {
        model.backscatter_infinity[c] = p[c][0];
        model.backscatter_coefficient[c] = p[c][1];
        model.residual_signal[c] = p[c][2];
        model.residual_decay[c] = p[c][3];
      }
      model.vignetting = v;
    }
  }
  // Per-channel RMS of the best fit.
  Eigen::Array3d squares = Eigen::Array3d::Zero();
  for (const RangeSample* s : dark) {
    const double vignette = 1.0 - model.vignetting * (1.0 - s->cos4);
    squares += (vignette * model.backscatter(s->range) - s->rgb.cast<double>()).square();
  }
  stats.rms = (squares / dark.size()).sqrt();
  return stats;
}

// The direct signal I / V - B(z) of an observation.
static Eigen::Array3d directSignal(const PointObservation& o, const WaterModel& model) {
  const double vignette = 1.0 - model.vignetting * (1.0 - o.cos4);
  return o.rgb.cast<double>() / vignette - model.backscatter(o.range);
}

// The joint refinement (WaterFitOptions::refine_jointly): every observation of a point, dark or
// not, in linear light, with the backscatter's B_inf and b free. Starts from the separate fits.
static void refineJointly(const std::vector<std::vector<const PointObservation*>>& points,
                          const WaterFitOptions& options, WaterModel& model,
                          std::vector<Eigen::Vector3d>& log_j) {
  Eigen::Vector3d beta = model.attenuation.matrix();
  Eigen::Matrix<double, 6, 1> bs;
  bs << model.backscatter_infinity.matrix(), model.backscatter_coefficient.matrix();
  ceres::Problem problem;
  for (size_t p = 0; p < points.size(); ++p) {
    for (const PointObservation* o : points[p]) {
      const double vignette = 1.0 - model.vignetting * (1.0 - o->cos4);
      for (int c = 0; c < 3; ++c) {
        const double jd = model.residual_signal[c] * std::exp(-model.residual_decay[c] * o->range);
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<JointResidual, 1, 3, 3, 6>(
                                     new JointResidual(c, o->range, o->rgb[c] / vignette, jd)),
                                 new ceres::HuberLoss(options.joint_loss_scale), log_j[p].data(),
                                 beta.data(), bs.data());
      }
    }
    // Channels the log fit had no signal for: start dark.
    for (int c = 0; c < 3; ++c) {
      if (log_j[p][c] == 0) log_j[p][c] = std::log(options.min_signal);
    }
  }
  for (int c = 0; c < 3; ++c) {
    problem.SetParameterLowerBound(beta.data(), c, 0.0);
    problem.SetParameterUpperBound(beta.data(), c, options.max_attenuation);
    problem.SetParameterLowerBound(bs.data(), c, 0.0);
    problem.SetParameterUpperBound(bs.data(), c, 1.0);
    problem.SetParameterLowerBound(bs.data(), 3 + c, 0.0);
    problem.SetParameterUpperBound(bs.data(), 3 + c, options.max_attenuation);
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    throw std::invalid_argument("joint attenuation/backscatter fit failed: " +
                                summary.BriefReport());
  }
  model.attenuation = beta.array();
  model.backscatter_infinity = bs.head<3>().array();
  model.backscatter_coefficient = bs.tail<3>().array();
}

AttenuationFitStats fitAttenuation(const std::vector<PointObservation>& observations,
                                   const WaterFitOptions& options, WaterModel& model) {
  // Group by point; keep points seen often enough over a wide enough span of ranges.
  std::map<int32_t, std::vector<const PointObservation*>> by_point;
  for (const PointObservation& o : observations) {
    if (o.range > 0 && std::isfinite(o.range)) by_point[o.point].push_back(&o);
  }
  std::vector<std::vector<const PointObservation*>> points;
  for (auto& [id, list] : by_point) {
    if (static_cast<int>(list.size()) < options.min_views) continue;
    float near = list.front()->range, far = near;
    for (const PointObservation* o : list) {
      near = std::min(near, o->range);
      far = std::max(far, o->range);
    }
    if (far >= options.min_range_ratio * near) points.push_back(std::move(list));
  }
  if (points.size() < 10) {
    throw std::invalid_argument(
        "attenuation fit: " + std::to_string(points.size()) +
        " surface points seen from >= " + std::to_string(options.min_views) +
        " views over a range ratio >= " + std::to_string(options.min_range_ratio) +
        " (at least 10 needed)");
  }
  AttenuationFitStats stats;
  stats.points = points.size();
  std::vector<Eigen::Vector3d> log_j(points.size(), Eigen::Vector3d::Zero());
  Eigen::Vector3d beta = Eigen::Vector3d::Zero();
  ceres::Problem problem;
  std::vector<ceres::ResidualBlockId> blocks;
  std::vector<int> block_channel;
  for (size_t p = 0; p < points.size(); ++p) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), count = Eigen::Vector3d::Zero();
    for (const PointObservation* o : points[p]) {
      const Eigen::Array3d signal = directSignal(*o, model);
      for (int c = 0; c < 3; ++c) {
        if (signal[c] < options.min_signal) continue;
        const double log_d = std::log(signal[c]);
        sum[c] += log_d;
        count[c] += 1;
        blocks.push_back(problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<AttenuationResidual, 1, 3, 3>(
                new AttenuationResidual(c, o->range, log_d)),
            new ceres::LossFunctionWrapper(new ceres::HuberLoss(1.0), ceres::TAKE_OWNERSHIP),
            log_j[p].data(), beta.data()));
        block_channel.push_back(c);
        ++stats.observations;
      }
    }
    for (int c = 0; c < 3; ++c) log_j[p][c] = count[c] > 0 ? sum[c] / count[c] : 0;
  }
  if (stats.observations == 0) {
    throw std::invalid_argument("attenuation fit: no observation above min_signal");
  }
  for (int c = 0; c < 3; ++c) {
    problem.SetParameterLowerBound(beta.data(), c, 0.0);
    problem.SetParameterUpperBound(beta.data(), c, options.max_attenuation);
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;  // the points eliminated: a 3x3 system
  solver.max_num_iterations = 100;
  // A convex start (Huber, wide), then the redescending Cauchy loss from there: started at
  // beta = 0, the Cauchy loss alone stays in the flat tail where most residuals begin.
  for (int stage = 0; stage < 2; ++stage) {
    if (stage == 1) {
      for (ceres::ResidualBlockId block : blocks) {
        auto* wrapper =
            const_cast<ceres::LossFunctionWrapper*>(static_cast<const ceres::LossFunctionWrapper*>(
                problem.GetLossFunctionForResidualBlock(block)));
        wrapper->Reset(new ceres::CauchyLoss(options.loss_scale), ceres::TAKE_OWNERSHIP);
      }
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (!summary.IsSolutionUsable()) {
      throw std::invalid_argument("attenuation fit failed: " + summary.BriefReport());
    }
  }
  model.attenuation = beta.array();
  Eigen::Array3d squares = Eigen::Array3d::Zero(), counts = Eigen::Array3d::Zero();
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = blocks;
  evaluate.apply_loss_function = false;
  std::vector<double> residuals;
  problem.Evaluate(evaluate, nullptr, &residuals, nullptr, nullptr);
  for (size_t i = 0; i < residuals.size(); ++i) {
    squares[block_channel[i]] += residuals[i] * residuals[i];
    counts[block_channel[i]] += 1;
  }
  stats.rms = (squares / counts.max(1.0)).sqrt();
  if (options.refine_jointly) refineJointly(points, options, model, log_j);
  for (size_t p = 0; p < points.size(); ++p) {
    PointColor color;
    color.point = points[p].front()->point;
    color.log_j = log_j[p].array();
    for (const PointObservation* o : points[p]) {
      color.observations += (directSignal(*o, model) >= options.min_signal).cast<int>();
    }
    stats.colors.push_back(color);
  }
  return stats;
}

void fitIlluminantGradient(const std::vector<PointColor>& colors,
                           const std::vector<Eigen::Vector3d>& positions,
                           const Eigen::Vector3d& origin, const WaterFitOptions& options,
                           WaterModel& model) {
  model.illuminant_origin = origin;
  // The gradient is fitted only along directions the points span (a flat floor says nothing
  // about the light's trend off its plane, and extrapolating one to the origin would be noise):
  // principal axes whose spread is below a fifth of the largest keep a zero component.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  size_t count = 0;
  for (const PointColor& color : colors) {
    if (color.point < 0 || static_cast<size_t>(color.point) >= positions.size()) {
      throw std::invalid_argument("illuminant fit: point " + std::to_string(color.point) +
                                  " has no position");
    }
    mean += positions[color.point];
    ++count;
  }
  if (count < 10) throw std::invalid_argument("illuminant fit: fewer than 10 points");
  mean /= static_cast<double>(count);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const PointColor& color : colors) {
    const Eigen::Vector3d d = positions[color.point] - mean;
    covariance += d * d.transpose() / static_cast<double>(count);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(covariance);
  const Eigen::Matrix3d basis = axes.eigenvectors();  // columns, increasing spread
  const Eigen::Vector3d spread = axes.eigenvalues().cwiseMax(0).cwiseSqrt();
  std::vector<int> flat;
  for (int i = 0; i < 3; ++i) {
    if (spread[i] < 0.2 * spread[2]) flat.push_back(i);
  }
  for (int c = 0; c < 3; ++c) {
    double a = 0;
    Eigen::Vector3d h = Eigen::Vector3d::Zero();  // the gradient in `basis`
    ceres::Problem problem;
    size_t used = 0;
    for (const PointColor& color : colors) {
      if (color.observations[c] == 0) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<GradientResidual, 1, 1, 3>(new GradientResidual(
              basis.transpose() * (positions[color.point] - origin), color.log_j[c])),
          new ceres::CauchyLoss(options.loss_scale * 5), &a, h.data());
      ++used;
    }
    if (used < 10) {
      throw std::invalid_argument("illuminant fit: " + std::to_string(used) +
                                  " points with a colour in channel " + std::string(1, "rgb"[c]) +
                                  " (at least 10 needed)");
    }
    if (!flat.empty()) problem.SetManifold(h.data(), new ceres::SubsetManifold(3, flat));
    ceres::Solver::Options solver;
    solver.max_num_iterations = 100;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (!summary.IsSolutionUsable()) {
      throw std::invalid_argument("illuminant fit failed: " + summary.BriefReport());
    }
    model.illuminant_gradient.row(c) = (basis * h).transpose();
  }
}

cv::Mat linearFromSrgb(const cv::Mat& bgr8) {
  cv::Mat lut(1, 256, CV_32F);
  for (int i = 0; i < 256; ++i) lut.at<float>(i) = srgbToLinear(i / 255.0f);
  cv::Mat out;
  cv::LUT(bgr8, lut, out);
  return out;
}

cv::Mat srgbFromLinear(const cv::Mat& linear) {
  const std::vector<float>& table = srgbTable();
  cv::Mat out(linear.size(), CV_8UC3);
  for (int y = 0; y < linear.rows; ++y) {
    const float* in = linear.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int i = 0; i < linear.cols * 3; ++i) {
      const float v = std::clamp(std::isfinite(in[i]) ? in[i] : 0.0f, 0.0f, 1.0f);
      o[i] = cv::saturate_cast<uint8_t>(table[static_cast<int>(v * 65536.0f + 0.5f)]);
    }
  }
  return out;
}

cv::Mat cos4Map(cv::Size size, double fx, double fy, double cx, double cy) {
  cv::Mat1f out(size);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const double u = (x - cx) / fx, w = (y - cy) / fy;
      const double cos2 = 1.0 / (1.0 + u * u + w * w);
      out(y, x) = static_cast<float>(cos2 * cos2);
    }
  }
  return out;
}

Eigen::Array3d restoreLinear(const Eigen::Array3d& rgb, double range, double cos4,
                             const WaterModel& model, double max_gain) {
  const double vignette = 1.0 - model.vignetting * (1.0 - cos4);
  const Eigen::Array3d gain = (model.attenuation * range).exp().min(max_gain);
  return (rgb / vignette - model.backscatter(range)).max(0.0) * gain;
}

cv::Mat restoreImage(const cv::Mat& bgr8, const cv::Mat& range, const cv::Mat& cos4,
                     const WaterModel& model, const WaterFitOptions& options,
                     const cv::Mat& illuminant) {
  if (bgr8.type() != CV_8UC3 || range.type() != CV_32F || range.size() != bgr8.size() ||
      (!cos4.empty() && (cos4.type() != CV_32F || cos4.size() != bgr8.size())) ||
      (!illuminant.empty() &&
       (illuminant.type() != CV_32FC3 || illuminant.size() != bgr8.size()))) {
    std::ostringstream what;
    what << "restoreImage: image " << bgr8.cols << "x" << bgr8.rows
         << " (8-bit BGR needed), range map " << range.cols << "x" << range.rows
         << ", vignetting map " << cos4.cols << "x" << cos4.rows << ": sizes differ or wrong types";
    throw std::invalid_argument(what.str());
  }
  float far = 0;
  for (auto it = range.begin<float>(); it != range.end<float>(); ++it) {
    if (std::isfinite(*it) && *it > far) far = *it;
  }
  const cv::Mat linear = linearFromSrgb(bgr8);
  cv::Mat restored(bgr8.size(), CV_32FC3);
  const Eigen::Array3d balance = model.white_balance;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < bgr8.rows; ++y) {
    const cv::Vec3f* in = linear.ptr<cv::Vec3f>(y);
    const float* z = range.ptr<float>(y);
    cv::Vec3f* out = restored.ptr<cv::Vec3f>(y);
    for (int x = 0; x < bgr8.cols; ++x) {
      const double r = std::isfinite(z[x]) && z[x] > 0 ? z[x] : far;
      const double k = cos4.empty() ? 1.0 : cos4.at<float>(y, x);
      const Eigen::Array3d rgb(in[x][2], in[x][1], in[x][0]);
      Eigen::Array3d j = restoreLinear(rgb, r, k, model, options.max_gain) * balance;
      if (!illuminant.empty()) {
        const cv::Vec3f e = illuminant.at<cv::Vec3f>(y, x);
        j /= Eigen::Array3d(e[2], e[1], e[0]).max(1.0 / options.max_gain);
      }
      out[x] =
          cv::Vec3f(static_cast<float>(j[2]), static_cast<float>(j[1]), static_cast<float>(j[0]));
    }
  }
  return srgbFromLinear(restored);
}

void writeWaterModel(const std::filesystem::path& file, const WaterModel& model,
                     const std::string& comment) {
  std::ostringstream out;
  out << std::setprecision(9);
  const auto triple = [&out](const char* key, const Eigen::Array3d& v) {
    out << key << ": [" << v[0] << ", " << v[1] << ", " << v[2] << "]\n";
  };
  out << "# " << comment << "\n";
  out << "# I = V (J exp(-attenuation z) + B(z)), B(z) = backscatter_infinity (1 - "
         "exp(-backscatter_coefficient z)) + residual_signal exp(-residual_decay z); [r, g, b], "
         "linear, z in the model's units\n";
  triple("backscatter_infinity", model.backscatter_infinity);
  triple("backscatter_coefficient", model.backscatter_coefficient);
  triple("residual_signal", model.residual_signal);
  triple("residual_decay", model.residual_decay);
  triple("attenuation", model.attenuation);
  out << "vignetting: " << model.vignetting << "\n";
  triple("white_balance", model.white_balance);
  out << "illuminant_gradient: [";
  for (int i = 0; i < 9; ++i) out << (i ? ", " : "") << model.illuminant_gradient(i / 3, i % 3);
  out << "]  # rows r, g, b; 1/unit\n";
  out << "illuminant_origin: [" << model.illuminant_origin.x() << ", "
      << model.illuminant_origin.y() << ", " << model.illuminant_origin.z() << "]\n";
  writeFileAtomically(file, out.str());
}

WaterModel readWaterModel(const std::filesystem::path& file) {
  YAML::Node root;
  try {
    root = config::loadYamlFile(file.string()).node();  // refuses alias cycles and bombs
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + ": cannot read: " + e.what());
  }
  WaterModel m;
  m.backscatter_infinity = readTriple(root, "backscatter_infinity", file);
  m.backscatter_coefficient = readTriple(root, "backscatter_coefficient", file);
  m.residual_signal = readTriple(root, "residual_signal", file);
  m.residual_decay = readTriple(root, "residual_decay", file);
  m.attenuation = readTriple(root, "attenuation", file);
  m.white_balance = readTriple(root, "white_balance", file);
  m.illuminant_origin = readTriple(root, "illuminant_origin", file).matrix();
  const YAML::Node gradient = root["illuminant_gradient"];
  if (!gradient || !gradient.IsSequence() || gradient.size() != 9) {
    throw std::runtime_error(file.string() + ": illuminant_gradient: expected 9 numbers");
  }
  for (int i = 0; i < 9; ++i) m.illuminant_gradient(i / 3, i % 3) = gradient[i].as<double>();
  if (!root["vignetting"]) throw std::runtime_error(file.string() + ": vignetting: missing");
  m.vignetting = root["vignetting"].as<double>();
  return m;
}

}  // namespace auv::recon::color
