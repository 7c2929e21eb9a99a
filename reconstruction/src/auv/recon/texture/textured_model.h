#pragma once
// A textured triangle mesh: positions, per-face-corner texture coordinates into atlas pages,
// the pages themselves. Written as Wavefront OBJ + MTL + PNG (MeshLab, Blender, Open3D read
// it), read back, and rendered from a pinhole camera for texture-fidelity checks (PSNR against
// the simulator's renderings at held-out views).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "auv/recon/texture/rasterizer.h"

namespace auv::recon::texture {

struct TexturedModel {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  /// Per face, the texture coordinates of its three corners, OBJ convention: u to the right,
  /// v up, (0, 0) the bottom-left corner of the page.
  std::vector<std::array<Eigen::Vector2f, 3>> face_uvs;
  std::vector<int> face_page;    ///< atlas page of each face
  std::vector<cv::Mat3b> pages;  ///< BGR atlas images

  /// Throws std::invalid_argument when the sizes or indices disagree.
  void validate() const;
};

/// Writes `<folder>/<stem>.obj`, `<stem>.mtl` and `<stem>_<page>.png` (one material per page).
/// Each file goes through a temporary name. Throws std::runtime_error naming a file it cannot
/// write.
void writeObj(const TexturedModel& model, const std::filesystem::path& folder,
              const std::string& stem = "model");

/// Reads an OBJ written by writeObj (or any triangle OBJ with `vt` and `map_Kd` materials):
/// `v`, `vt`, `f v/vt[/vn]`, `usemtl`, `mtllib`. Throws std::runtime_error naming the file and
/// line for what it cannot read.
TexturedModel readObj(const std::filesystem::path& obj);

struct Rendering {
  cv::Mat3b image;  ///< BGR; background where nothing was drawn
  cv::Mat1b mask;   ///< 255 where the model covers the pixel
  cv::Mat1f depth;  ///< camera z, +inf where uncovered
};

/// Renders the model from `view` (z-buffer, perspective-correct texture coordinates, bilinear
/// texture lookup).
Rendering renderTexturedModel(const TexturedModel& model, const ViewGeometry& view,
                              const cv::Vec3b& background = cv::Vec3b(0, 0, 0));

/// The model's colour (BGR, 0..255) at a point of `face` given by barycentric weights
/// (bilinear lookup in its page).
Eigen::Vector3f sampleFace(const TexturedModel& model, int face, const Eigen::Vector3d& weights);

/// Peak signal-to-noise ratio (dB, 8-bit) of `image` against `reference` over the pixels where
/// `mask` is non-zero (all pixels when empty). +inf when identical.
double psnr(const cv::Mat3b& image, const cv::Mat3b& reference, const cv::Mat1b& mask = {});

}  // namespace auv::recon::texture
