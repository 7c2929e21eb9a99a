#pragma once
// Ruderman's lαβ opponent colour space (Ruderman, Cronin, Chiao 1998; paper reference [51]),
// with the RGB -> LMS matrix of Reinhard et al. 2001 ("Color transfer between images"):
//
//   LMS = M_lms * RGB_linear,   (l, α, β) = diag(1/√3, 1/√6, 1/√2) [1 1 1; 1 1 -2; 1 -1 0] log10
//   LMS
//
// l is the luminance (√3 × log10 of the geometric mean of L, M, S), α a yellow-blue and β a
// red-green opponent axis; a neutral (grey) pixel has α = β = 0. Images are 8-bit sRGB (BGR
// order, OpenCV's); they are linearised with the sRGB transfer function before M_lms.

#include <opencv2/core.hpp>

namespace auv::recon::color {

/// Linear values below this are raised to it before the logarithm (log10 of 0 is -inf);
/// it lies below half an 8-bit sRGB step, so the round trip is exact for 8-bit images.
constexpr float kLinearFloor = 1e-4f;

/// 8-bit BGR (CV_8UC3) -> lαβ (CV_32FC3, channels l, α, β). Throws std::invalid_argument for
/// another type.
cv::Mat bgrToLalphabeta(const cv::Mat& bgr);

/// lαβ (CV_32FC3) -> 8-bit BGR, clipping colours outside the sRGB gamut.
cv::Mat lalphabetaToBgr(const cv::Mat& lalphabeta);

/// sRGB transfer function (IEC 61966-2-1) both ways, on [0, 1].
float srgbToLinear(float encoded);
float linearToSrgb(float linear);

}  // namespace auv::recon::color
