#pragma once
// The photo half of `auv recon import` (import_stage.h): a folder of photos -> keyframes of one
// camera per group of photos that share a size, a camera model and a focal length.

#include "auv/recon/import/import_stage.h"

namespace auv::recon::import {

/// Image files `auv recon import --images` reads (lower case, with the dot).
const std::vector<std::string>& photoExtensions();

/// Why an encoded image cannot be imported ("truncated JPEG: ..."), or empty when it can.
/// `decoded` receives the image as stored (before EXIF orientation) when it can.
std::string photoDamage(const std::vector<unsigned char>& encoded, cv::Mat* decoded);

/// Imports the photos of `options.images` into `result`; see runImportStage.
void importPhotos(const Survey& survey, const ImportStageOptions& options,
                  ImportStageResult& result);

}  // namespace auv::recon::import
