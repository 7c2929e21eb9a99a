// Colour correction figures (issue 6; paper section 3.2), written to
// <results dir>/color_bench_<time>.md:
//
// 1. Real underwater photos (--u45 DIR, ../shared/data/u45_underwater): per image, before and
//    after correctColor, the colour cast (|mean α|, |mean β| in lαβ; spread of the RGB channel
//    means), the RMS contrast of the luminance, the colourfulness (Hasler & Süsstrunk 2003),
//    the SIFT keypoints, and the SIFT matches that survive Lowe's ratio test and a RANSAC
//    homography between the image and a second view of it (a known homography: 8 degrees,
//    0.85 scale, perspective), each view corrected on its own as the pipeline does. U45's
//    photos are 45 different scenes, so "neighbouring views" are made this way.
// 2. Simulator footage with the true colours known (--sim-water A.mp4 --sim-clear B.mp4, the
//    same trajectory rendered with the scenario's water and with water: attenuation,
//    backscatter and veiling light all 0, see bench/README.md): per frame, the mean angular
//    error of the linear RGB (brightness-blind) and the CIE76 colour difference after matching
//    the mean luminance, against the water-free frame, for the raw frame, the lαβ correction
//    and, as a reference point, a grey-world gain in RGB.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/color/correction.h"
#include "auv/recon/color/lalphabeta.h"

namespace fs = std::filesystem;
using namespace auv::recon::color;

namespace {

std::string timestamp() {
  char text[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(text, sizeof(text), "%Y%m%d_%H%M%S", std::localtime(&now));
  return text;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

struct Stats {
  double cast_alpha = 0, cast_beta = 0, channel_spread = 0, contrast = 0, colourfulness = 0;
  int keypoints = 0;
};

Stats statistics(const cv::Mat& bgr) {
  Stats s;
  const cv::Scalar lab = cv::mean(bgrToLalphabeta(bgr));
  s.cast_alpha = std::abs(lab[1]);
  s.cast_beta = std::abs(lab[2]);
  const cv::Scalar channels = cv::mean(bgr);
  const double high = std::max({channels[0], channels[1], channels[2]});
  const double low = std::min({channels[0], channels[1], channels[2]});
  s.channel_spread = (high - low) / std::max(1.0, (channels[0] + channels[1] + channels[2]) / 3);
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  cv::Scalar m, d;
  cv::meanStdDev(gray, m, d);
  s.contrast = d[0] / 255.0;
  // Hasler & Süsstrunk: rg = R - G, yb = (R + G) / 2 - B.
  std::vector<cv::Mat> bgr_planes;
  cv::Mat f;
  bgr.convertTo(f, CV_32FC3);
  cv::split(f, bgr_planes);
  const cv::Mat rg = bgr_planes[2] - bgr_planes[1];
  const cv::Mat yb = 0.5 * (bgr_planes[2] + bgr_planes[1]) - bgr_planes[0];
  cv::Scalar mrg, drg, myb, dyb;
  cv::meanStdDev(rg, mrg, drg);
  cv::meanStdDev(yb, myb, dyb);
  s.colourfulness = std::hypot(drg[0], dyb[0]) + 0.3 * std::hypot(mrg[0], myb[0]);
  return s;
}

/// Verified SIFT matches between `a` and `b` (ratio 0.8, RANSAC homography 3 px).
int verifiedMatches(const cv::Mat& a, const cv::Mat& b, int* keypoints_a) {
  auto sift = cv::SIFT::create();
  std::vector<cv::KeyPoint> ka, kb;
  cv::Mat da, db;
  sift->detectAndCompute(a, cv::noArray(), ka, da);
  sift->detectAndCompute(b, cv::noArray(), kb, db);
  if (keypoints_a) *keypoints_a = static_cast<int>(ka.size());
  if (ka.size() < 4 || kb.size() < 4) return 0;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(da, db, knn, 2);
  std::vector<cv::Point2f> pa, pb;
  for (const auto& m : knn) {
    if (m.size() == 2 && m[0].distance < 0.8f * m[1].distance) {
      pa.push_back(ka[m[0].queryIdx].pt);
      pb.push_back(kb[m[0].trainIdx].pt);
    }
  }
  if (pa.size() < 4) return 0;
  cv::Mat inliers;
  cv::findHomography(pa, pb, cv::RANSAC, 3.0, inliers, 5000, 0.999);
  return inliers.empty() ? 0 : cv::countNonZero(inliers);
}

/// The second view of a U45 image: a known homography about the centre.
cv::Mat secondView(const cv::Mat& image) {
  const cv::Point2f centre(image.cols / 2.f, image.rows / 2.f);
  cv::Mat A = cv::getRotationMatrix2D(centre, 8.0, 0.85);
  cv::Mat H = cv::Mat::eye(3, 3, CV_64F);
  A.copyTo(H(cv::Rect(0, 0, 3, 2)));
  H.at<double>(2, 0) = 2e-4;
  H.at<double>(2, 1) = -1e-4;
  cv::Mat out;
  cv::warpPerspective(image, out, H, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

std::string u45Section(const fs::path& folder, const ColorOptions& options) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.path().extension() == ".png" || e.path().extension() == ".jpg") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<double> before_alpha, after_alpha, before_beta, after_beta, before_spread,
      after_spread, before_contrast, after_contrast, before_colour, after_colour, gain;
  long kp_before = 0, kp_after = 0, matches_before = 0, matches_after = 0;
  int improved = 0, worse = 0;
  for (const auto& file : files) {
    const cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (image.empty()) continue;
    const cv::Mat corrected = correctColor(image, options).image;
    const Stats b = statistics(image), a = statistics(corrected);
    before_alpha.push_back(b.cast_alpha);
    after_alpha.push_back(a.cast_alpha);
    before_beta.push_back(b.cast_beta);
    after_beta.push_back(a.cast_beta);
    before_spread.push_back(b.channel_spread);
    after_spread.push_back(a.channel_spread);
    before_contrast.push_back(b.contrast);
    after_contrast.push_back(a.contrast);
    before_colour.push_back(b.colourfulness);
    after_colour.push_back(a.colourfulness);
    const cv::Mat other = secondView(image);
    int kb = 0, ka = 0;
    const int mb = verifiedMatches(image, other, &kb);
    const int ma = verifiedMatches(corrected, correctColor(other, options).image, &ka);
    kp_before += kb;
    kp_after += ka;
    matches_before += mb;
    matches_after += ma;
    if (ma > mb) ++improved;
    if (ma < mb) ++worse;
    gain.push_back(mb > 0 ? static_cast<double>(ma) / mb : 0);
    std::cerr << file.filename().string() << ": matches " << mb << " -> " << ma << ", contrast "
              << b.contrast << " -> " << a.contrast << "\n";
  }
  std::ostringstream out;
  out << "## U45 (" << files.size() << " real underwater photos, " << folder.string() << ")\n\n"
      << "| statistic (mean over images) | before | after |\n|---|---|---|\n";
  auto row = [&](const char* name, const std::vector<double>& b, const std::vector<double>& a) {
    char text[256];
    std::snprintf(text, sizeof(text), "| %s | %.4f | %.4f |\n", name, mean(b), mean(a));
    out << text;
  };
  row("colour cast |mean α| (lαβ)", before_alpha, after_alpha);
  row("colour cast |mean β| (lαβ)", before_beta, after_beta);
  row("RGB channel-mean spread (max-min)/mean", before_spread, after_spread);
  row("RMS contrast of the luminance (0-1)", before_contrast, after_contrast);
  row("colourfulness (Hasler-Süsstrunk)", before_colour, after_colour);
  char text[512];
  std::snprintf(text, sizeof(text),
                "| SIFT keypoints (total) | %ld | %ld |\n"
                "| verified SIFT matches with the second view (total) | %ld | %ld |\n\n"
                "Matches: more after correction in %d images, fewer in %d; median ratio "
                "after/before %.2f.\n\n",
                kp_before, kp_after, matches_before, matches_after, improved, worse, median(gain));
  out << text;
  return out.str();
}

/// Linear RGB (float, 0..1) of an 8-bit BGR image.
cv::Mat linearRgb(const cv::Mat& bgr) {
  cv::Mat out(bgr.size(), CV_32FC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      out.at<cv::Vec3f>(y, x) = cv::Vec3f(srgbToLinear(p[2] / 255.f), srgbToLinear(p[1] / 255.f),
                                          srgbToLinear(p[0] / 255.f));
    }
  }
  return out;
}

cv::Mat greyWorldRgb(const cv::Mat& bgr) {
  cv::Mat lin = linearRgb(bgr);
  const cv::Scalar m = cv::mean(lin);
  const double grey = (m[0] + m[1] + m[2]) / 3;
  cv::Mat out(bgr.size(), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3f p = lin.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) {
        const float v =
            std::clamp(static_cast<float>(p[c] * grey / std::max(m[c], 1e-6)), 0.f, 1.f);
        out.at<cv::Vec3b>(y, x)[2 - c] = cv::saturate_cast<uchar>(linearToSrgb(v) * 255.f);
      }
    }
  }
  return out;
}

struct ColourError {
  double angle_deg = 0, delta_e = 0;
};

/// Errors of `image` against `truth` over `mask` (linear RGB angle; CIE76 after scaling the
/// image's linear RGB to the truth's mean luminance).
ColourError colourError(const cv::Mat& image, const cv::Mat& truth, const cv::Mat& mask) {
  const cv::Mat a = linearRgb(image), t = linearRgb(truth);
  double angle = 0, la = 0, lt = 0;
  int n = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      if (!mask.at<uchar>(y, x)) continue;
      const cv::Vec3f u = a.at<cv::Vec3f>(y, x), v = t.at<cv::Vec3f>(y, x);
      const double cosine = u.dot(v) / (cv::norm(u) * cv::norm(v) + 1e-12);
      angle += std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / CV_PI;
      la += 0.2126 * u[0] + 0.7152 * u[1] + 0.0722 * u[2];
      lt += 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
      ++n;
    }
  }
  ColourError e;
  if (n == 0) return e;
  e.angle_deg = angle / n;
  const float scale = static_cast<float>(lt / std::max(la, 1e-9));
  cv::Mat as = cv::min(a * scale, 1.0), lab_a, lab_t;
  // LRGB: the input is linear (COLOR_RGB2Lab would apply the sRGB curve again).
  cv::cvtColor(as, lab_a, cv::COLOR_LRGB2Lab);
  cv::cvtColor(t, lab_t, cv::COLOR_LRGB2Lab);
  double de = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      if (!mask.at<uchar>(y, x)) continue;
      de += cv::norm(lab_a.at<cv::Vec3f>(y, x) - lab_t.at<cv::Vec3f>(y, x));
    }
  }
  e.delta_e = de / n;
  return e;
}

std::string simSection(const fs::path& water, const fs::path& clear, const ColorOptions& options,
                       int every) {
  cv::VideoCapture a(water.string(), cv::CAP_FFMPEG), b(clear.string(), cv::CAP_FFMPEG);
  if (!a.isOpened() || !b.isOpened()) {
    std::cerr << "cannot open " << water << " or " << clear << "\n";
    std::exit(1);
  }
  std::vector<double> raw_angle, raw_de, lab_angle, lab_de, gw_angle, gw_de, coverage;
  cv::Mat fw, fc;
  for (int index = 0; a.read(fw) && b.read(fc); ++index) {
    if (index % every != 0) continue;
    // Pixels that see the scene in the clear render (open water is black there).
    cv::Mat gray;
    cv::cvtColor(fc, gray, cv::COLOR_BGR2GRAY);
    const cv::Mat mask = gray > 12;
    coverage.push_back(cv::countNonZero(mask) / static_cast<double>(mask.total()));
    if (coverage.back() < 0.05) continue;
    const ColourError raw = colourError(fw, fc, mask);
    const ColourError lab = colourError(correctColor(fw, options).image, fc, mask);
    const ColourError gw = colourError(greyWorldRgb(fw), fc, mask);
    raw_angle.push_back(raw.angle_deg);
    raw_de.push_back(raw.delta_e);
    lab_angle.push_back(lab.angle_deg);
    lab_de.push_back(lab.delta_e);
    gw_angle.push_back(gw.angle_deg);
    gw_de.push_back(gw.delta_e);
    std::cerr << "frame " << index << ": angle " << raw.angle_deg << " -> " << lab.angle_deg
              << " deg (grey-world RGB " << gw.angle_deg << "), dE " << raw.delta_e << " -> "
              << lab.delta_e << "\n";
  }
  std::ostringstream out;
  char text[1024];
  std::snprintf(text, sizeof(text),
                "## Simulator footage against the water-free render of the same views\n\n"
                "%s vs %s: %zu frames (every %d), scene pixels %.0f%% of each frame (mean).\n\n"
                "| frames | mean angular error, linear RGB (deg) | mean CIE76 ΔE (luminance "
                "matched) |\n|---|---|---|\n"
                "| as filmed (before) | %.2f | %.2f |\n"
                "| lαβ correction (after) | %.2f | %.2f |\n"
                "| reference point: grey-world gains in RGB | %.2f | %.2f |\n\n",
                water.string().c_str(), clear.string().c_str(), raw_angle.size(), every,
                100 * mean(coverage), mean(raw_angle), mean(raw_de), mean(lab_angle), mean(lab_de),
                mean(gw_angle), mean(gw_de));
  out << text;
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  fs::path u45, water, clear, results_dir = "bench_results";
  int every = 1;
  ColorOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << arg << ": missing value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--u45") {
      u45 = value();
    } else if (arg == "--sim-water") {
      water = value();
    } else if (arg == "--sim-clear") {
      clear = value();
    } else if (arg == "--every") {
      every = std::max(1, std::stoi(value()));
    } else if (arg == "--results-dir") {
      results_dir = value();
    } else {
      std::cerr << "usage: color_bench [--u45 DIR] [--sim-water A.mp4 --sim-clear B.mp4 "
                   "[--every N]] [--results-dir DIR]\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  if (u45.empty() && water.empty()) {
    std::cerr << "nothing to measure: --u45 DIR and/or --sim-water/--sim-clear\n";
    return 2;
  }
  std::ostringstream report;
  report << "# color_bench " << timestamp() << "\n\nColorOptions: chroma_strength "
         << options.chroma_strength << ", cutoff_low " << options.cutoff_low << ", cutoff_high "
         << options.cutoff_high << ".\n\n";
  if (!u45.empty()) report << u45Section(u45, options);
  if (!water.empty()) report << simSection(water, clear, options, every);
  std::cout << report.str();
  fs::create_directories(results_dir);
  const fs::path file = results_dir / ("color_bench_" + timestamp() + ".md");
  std::ofstream(file) << report.str();
  std::cout << "results: " << file.string() << std::endl;
  return 0;
}
