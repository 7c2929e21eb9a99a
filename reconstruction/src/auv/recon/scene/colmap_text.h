#pragma once
// COLMAP's text model format (cameras.txt, images.txt, points3D.txt), so that a reconstruction
// opens in COLMAP's GUI and COLMAP's models (or the simulator's ground truth) can be read.
// https://colmap.github.io/format.html#text-format
//
// Files use COLMAP's pixel convention (centre of the top-left pixel at 0.5, 0.5); in memory we
// use OpenCV's (0, 0): principal points and keypoints are shifted by 0.5 when read and written.

#include <filesystem>
#include <map>

#include "auv/recon/scene/reconstruction.h"

namespace auv::recon::scene {

/// Reads `<folder>/cameras.txt`, `images.txt` and `points3D.txt` (points optional: a missing
/// file gives no points). Errors name the file and line.
Reconstruction readColmapText(const std::filesystem::path& folder);

/// Writes the three files into `folder` (created), each through a temporary name.
void writeColmapText(const Reconstruction& reconstruction, const std::filesystem::path& folder);

/// The single files, for ground truth split over several (`images_<camera>.txt`).
std::map<uint32_t, Camera> readColmapCameras(const std::filesystem::path& file);
/// Images of one file (poses and keypoints; the second line of an entry may be empty).
std::map<uint32_t, Image> readColmapImages(const std::filesystem::path& file);
std::map<uint64_t, Point3D> readColmapPoints(const std::filesystem::path& file);

}  // namespace auv::recon::scene
