#include "auv/recon/texture/texturer.h"

#include <chrono>
#include <iostream>
#include <set>

#include "auv/recon/common/progress.h"
#include "auv/recon/common/stage_error.h"

namespace auv::recon::texture {

namespace {
double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

TextureResult textureMesh(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                          const ImageLoader& images, const TextureOptions& options,
                          const ImageLoader& masks) {
  options.check();
  if (mesh.faces.empty()) throw StageError("texture", "the mesh has no faces");
  if (views.empty()) throw StageError("texture", "no views to texture from");
  if (mesh.face_normals.size() != mesh.faces.size()) {
    throw std::invalid_argument("texture: face normals missing (FaceMesh::computeFaceNormals)");
  }
  TextureResult result;
  TextureStats& stats = result.stats;
  stats.faces = mesh.faces.size();
  stats.views = views.size();

  // Visibility, data term and colours per (face, view).
  auto start = std::chrono::steady_clock::now();
  {
    Progress progress("texture: visibility", "views", views.size());
    const ImageLoader counted = [&](int view) {
      cv::Mat image = images(view);
      progress.advance();
      return image;
    };
    result.observations = observeFaces(mesh, views, counted, options.selection, masks);
  }
  for (const auto& face : result.observations) stats.observations += face.size();
  if (options.selection.photo_consistency) {
    stats.rejected_observations = rejectInconsistentViews(result.observations, options.selection);
  }
  stats.seconds_visibility = since(start);
  for (const auto& face : result.observations) stats.faces_seen += face.empty() ? 0 : 1;
  stats.faces_unseen = stats.faces - stats.faces_seen;
  if (stats.faces_seen == 0) {
    throw StageError("texture",
                     "no face of the mesh (" + std::to_string(stats.faces) +
                         " faces) is seen by any of the " + std::to_string(views.size()) +
                         " views (wrong poses, or the mesh is not in the model's frame)");
  }

  // Labelling.
  start = std::chrono::steady_clock::now();
  const std::vector<std::pair<int, int>> adjacency = mesh.faceAdjacency();
  ViewSelectionResult selection = selectViews(result.observations, adjacency, options.selection);
  result.labels = std::move(selection.labels);
  stats.greedy_energy = selection.greedy_energy;
  stats.energy = selection.energy;
  stats.greedy_seams = selection.greedy_seams;
  stats.seams = selection.seams;
  stats.cycles = selection.cycles;
  stats.views_used = std::set<int>(result.labels.begin(), result.labels.end()).size() -
                     (stats.faces_unseen > 0 ? 1 : 0);
  stats.seconds_selection = since(start);
  std::cerr << "texture: " << stats.faces_seen << " of " << stats.faces << " faces seen, "
            << stats.rejected_observations << " of " << stats.observations
            << " observations rejected as inconsistent; MRF energy " << stats.energy << " (greedy "
            << stats.greedy_energy << "), seams " << stats.seams << " (greedy "
            << stats.greedy_seams << "), " << stats.views_used << " views used" << std::endl;

  // Global seam levelling.
  start = std::chrono::steady_clock::now();
  ColorOffsets offsets;
  if (options.global_leveling) {
    SeamLevelingResult leveling = levelSeams(mesh, views, result.labels, images, options.leveling);
    offsets = std::move(leveling.offsets);
    stats.leveling = std::move(leveling);
    stats.leveling.offsets = {};
  }
  stats.seconds_leveling = since(start);

  // Patches, local blending, atlas.
  start = std::chrono::steady_clock::now();
  AtlasResult atlas =
      buildAtlas(mesh, views, result.labels, result.observations, offsets, images, options.atlas);
  result.model = std::move(atlas.model);
  stats.atlas = atlas.stats;
  stats.seconds_atlas = since(start);
  return result;
}

}  // namespace auv::recon::texture
