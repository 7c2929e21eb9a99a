#pragma once
// Depth maps on disk and normals from depth.
//
// File format: COLMAP's dense array format (`<width>&<height>&<channels>&` in ASCII, then
// float32 little-endian values channel by channel, each row-major), so COLMAP's
// read_write_dense.py reads them. A depth of 0 means "no depth".

#include <filesystem>

#include <opencv2/core.hpp>

#include "auv/recon/dense/view.h"

namespace auv::recon::dense {

/// Writes a CV_32FC1 or CV_32FC3 image through a temporary name. Throws std::runtime_error
/// naming the file when it cannot write.
void writeDenseArray(const std::filesystem::path& file, const cv::Mat& image);

/// Reads what writeDenseArray wrote (1 or 3 channels). Throws std::runtime_error naming the file
/// for a missing, truncated or malformed file.
cv::Mat readDenseArray(const std::filesystem::path& file);

/// World-frame unit normals (CV_32FC3, x y z) of a depth map of `view` (same size), from the
/// cross product of central differences `step` px apart (one-sided at holes), oriented towards
/// the camera; (0, 0, 0) where the depth or both of its neighbours along an axis are missing.
cv::Mat normalsFromDepth(const cv::Mat& depth, const View& view, int step = 1);

}  // namespace auv::recon::dense
