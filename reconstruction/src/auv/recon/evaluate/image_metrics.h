#pragma once
// Texture fidelity (issue 7): the textured model re-rendered at held-out ground-truth views
// (frames that were not keyframes) compared with the simulator's own rendering of those
// frames, by PSNR over the pixels the model covers.
//
// The simulator's frames carry the water (attenuation, backscatter) and the model carries the
// colour-corrected texture (paper section 3.2), so besides the raw PSNR we give the PSNR after
// the best per-channel gain and offset (least squares over the covered pixels): it measures
// whether the texture is in the right place and sharp, not whether the colour correction
// undoes the water.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::evaluate {

struct PsnrResult {
  double psnr_db = 0;       ///< raw; +infinity for identical images
  double psnr_gain_db = 0;  ///< after a per-channel gain + offset fitted on the pixels
  double mse = 0;           ///< mean squared error per channel value (0..255 scale)
  size_t pixels = 0;        ///< pixels compared
};

/// PSNR of `test` against `reference` (same size and type, 8-bit, 1 or 3 channels) over the
/// non-zero pixels of `mask` (CV_8U, same size; empty = every pixel), peak 255. Throws
/// std::invalid_argument for mismatched images; pixels = 0 and psnr 0 when the mask is empty.
PsnrResult psnr(const cv::Mat& reference, const cv::Mat& test, const cv::Mat& mask = cv::Mat());

/// CIEDE2000 colour difference of two CIELAB colours (L 0-100; Sharma, Wu and Dalal 2005).
double ciede2000(const cv::Vec3d& lab1, const cv::Vec3d& lab2);

struct DeltaEResult {
  double mean = 0, median = 0;  ///< CIEDE2000 over the pixels
  size_t pixels = 0;
};

/// CIEDE2000 between two 8-bit BGR sRGB images (same size, CV_8UC3) over the non-zero pixels of
/// `mask` (CV_8U, empty = all), through OpenCV's sRGB -> CIELAB (D65). Throws
/// std::invalid_argument for mismatched images.
DeltaEResult deltaE2000(const cv::Mat& reference, const cv::Mat& test,
                        const cv::Mat& mask = cv::Mat());

/// Frame `frame` (from 0) of a video, read by decoding from the start (seeking in H.264 is
/// not frame-exact); throws StageError("evaluate", ...) naming the video when it has fewer
/// frames or cannot be opened.
cv::Mat readVideoFrame(const std::filesystem::path& video, int64_t frame);

/// Several frames of one video in one decoding pass, in the order of `frames` (sorted inside).
std::vector<cv::Mat> readVideoFrames(const std::filesystem::path& video,
                                     const std::vector<int64_t>& frames);

/// Up to `count` held-out frames of a video of `frame_count` frames: frames midway between
/// consecutive keyframes (`keyframes` sorted or not), the widest gaps first, so they are as
/// far as possible from any image the texture was made from.
std::vector<int64_t> heldOutFrames(std::vector<int64_t> keyframes, int64_t frame_count,
                                   size_t count);

}  // namespace auv::recon::evaluate
