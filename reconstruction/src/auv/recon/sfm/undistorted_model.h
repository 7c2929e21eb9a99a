#pragma once
// The pinhole workspace of a model whose cameras have a lens distortion (a self-calibrated
// camera's k1, k2): dense matching and texturing work on pinhole images, so the images of such
// cameras are remapped (calibration/undistort.h, every output pixel valid) and the model is
// rewritten with PINHOLE cameras and undistorted keypoints, as COLMAP's image_undistorter does.
//
//   undistorted/<camera>/<file>.png   the images (those of pinhole cameras linked or copied)
//   undistorted/sparse/               the model, COLMAP text (same poses and points)
//
// Survey::pinholeWorkspace() points dense and texture at it when it exists.

#include <filesystem>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::sfm {

/// The model with each distorted camera replaced by the pinhole camera of its undistorted
/// images and the keypoints moved accordingly.
scene::Reconstruction undistortedModel(const scene::Reconstruction& model);

/// Writes `folder` (a staging folder): the remapped images of `images` (the corrected/ folder)
/// and `sparse/`. Throws StageError("sfm", ...) naming an image it cannot read or write.
void writeUndistortedWorkspace(const scene::Reconstruction& model,
                               const std::filesystem::path& images,
                               const std::filesystem::path& folder);

}  // namespace auv::recon::sfm
