#pragma once
// The video half of `auv recon import` (import_stage.h): one video file -> recordings/<camera>/
// with its frames sidecar (frame,camera_time_s,sim_time_s: the container's times), for the
// keyframes stage.

#include "auv/recon/import/import_stage.h"

namespace auv::recon::import {

/// Imports `options.video` into `result`; see runImportStage.
void importVideo(const Survey& survey, const ImportStageOptions& options,
                 ImportStageResult& result);

}  // namespace auv::recon::import
