#include "auv/recon/color/lalphabeta.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace auv::recon::color {

namespace {

/// Reinhard et al. 2001, RGB (linear, ITU-R BT.709 primaries) -> LMS cone space.
const cv::Matx33d kRgbToLms(0.3811, 0.5783, 0.0402,  //
                            0.1967, 0.7244, 0.0782,  //
                            0.0241, 0.1288, 0.8444);

/// log10 LMS -> lαβ (Ruderman et al. 1998).
cv::Matx33d logLmsToLab() {
  const cv::Matx33d scale(1 / std::sqrt(3.0), 0, 0, 0, 1 / std::sqrt(6.0), 0, 0, 0,
                          1 / std::sqrt(2.0));
  const cv::Matx33d mix(1, 1, 1, 1, 1, -2, 1, -1, 0);
  return scale * mix;
}

struct Tables {
  std::array<float, 256> decode;  ///< 8-bit sRGB -> linear
  static constexpr int kEncodeSize = 65536;
  std::vector<uint8_t> encode;  ///< linear in [0, 1] sampled at kEncodeSize -> 8-bit sRGB
  cv::Matx33f forward_lms;      ///< RGB -> LMS
  cv::Matx33f forward_lab;      ///< ln LMS -> lαβ (log10 folded in)
  cv::Matx33f inverse_lab;      ///< lαβ -> ln LMS
  cv::Matx33f inverse_lms;      ///< LMS -> RGB

  Tables() : encode(kEncodeSize) {
    for (int i = 0; i < 256; ++i) decode[i] = srgbToLinear(i / 255.f);
    for (int i = 0; i < kEncodeSize; ++i) {
      const float v = linearToSrgb(static_cast<float>(i) / (kEncodeSize - 1));
      encode[i] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.f, 1.f) * 255.f));
    }
    const cv::Matx33d lab = logLmsToLab() * (1.0 / std::log(10.0));
    forward_lms = kRgbToLms;
    forward_lab = lab;
    inverse_lab = lab.inv();
    inverse_lms = kRgbToLms.inv();
  }
};

const Tables& tables() {
  static const Tables t;
  return t;
}

}  // namespace

float srgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

cv::Mat bgrToLalphabeta(const cv::Mat& bgr) {
  if (bgr.type() != CV_8UC3) {
    throw std::invalid_argument("bgrToLalphabeta: expected an 8-bit 3-channel BGR image");
  }
  const Tables& t = tables();
  cv::Mat out(bgr.size(), CV_32FC3);
  cv::parallel_for_(cv::Range(0, bgr.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3b* in = bgr.ptr<cv::Vec3b>(y);
      cv::Vec3f* o = out.ptr<cv::Vec3f>(y);
      for (int x = 0; x < bgr.cols; ++x) {
        const cv::Vec3f rgb(t.decode[in[x][2]], t.decode[in[x][1]], t.decode[in[x][0]]);
        cv::Vec3f lms = t.forward_lms * rgb;
        for (int c = 0; c < 3; ++c) lms[c] = std::log(std::max(lms[c], kLinearFloor));
        o[x] = t.forward_lab * lms;
      }
    }
  });
  return out;
}

cv::Mat lalphabetaToBgr(const cv::Mat& lab) {
  if (lab.type() != CV_32FC3) {
    throw std::invalid_argument("lalphabetaToBgr: expected a CV_32FC3 lαβ image");
  }
  const Tables& t = tables();
  cv::Mat out(lab.size(), CV_8UC3);
  constexpr float kTop = Tables::kEncodeSize - 1;
  cv::parallel_for_(cv::Range(0, lab.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec3f* in = lab.ptr<cv::Vec3f>(y);
      cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
      for (int x = 0; x < lab.cols; ++x) {
        cv::Vec3f lms = t.inverse_lab * in[x];
        for (int c = 0; c < 3; ++c) lms[c] = std::exp(lms[c]);
        const cv::Vec3f rgb = t.inverse_lms * lms;
        for (int c = 0; c < 3; ++c) {
          const float v = std::clamp(rgb[c], 0.f, 1.f);
          o[x][2 - c] = t.encode[static_cast<int>(v * kTop + 0.5f)];
        }
      }
    }
  });
  return out;
}

}  // namespace auv::recon::color
