#include "auv/recon/texture/texture_stage.h"

#include <chrono>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/masks/mask.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/texture/image_cache.h"

namespace fs = std::filesystem;

namespace auv::recon::texture {

void TextureStageOptions::check() const {
  texture.check();
  AUV_RECON_CHECK_OPTION(image_cache >= 1, image_cache, "must be >= 1");
  AUV_RECON_CHECK_OPTION(images == "auto" || images == "corrected" || images == "restored", images,
                         "must be auto, corrected or restored");
}

void TextureStageOptions::bind(OptionSet& set) {
  ViewSelectionOptions& v = texture.selection;
  SeamLevelingOptions& l = texture.leveling;
  AtlasOptions& a = texture.atlas;
  set.add("data_term", &v.data_term, "gmi (gradient magnitude integral) or area");
  set.add("gradient_floor", &v.gradient_floor, "grey levels/px added to the gradient (GMI)");
  set.add("min_view_cosine", &v.min_view_cosine, "cos of the largest viewing angle");
  set.add("depth_tolerance", &v.depth_tolerance, "relative z-buffer tolerance (occlusion)");
  set.add("smoothness", &v.smoothness, "Potts weight of a seam (data cost in [0, 1])");
  set.add("max_cycles", &v.max_cycles, "alpha-expansion cycles at most");
  set.add("use_mrf", &v.use_mrf, "false: greedy per-face view (comparison only)");
  set.add("photo_consistency", &v.photo_consistency, "reject views that see an occluder");
  set.add("photo_consistency_sigma", &v.photo_consistency_sigma,
          "mean-shift bandwidth floor (0..255 colour units)");
  set.add("photo_consistency_threshold", &v.photo_consistency_threshold,
          "reject below this Gaussian weight");
  set.add("global_leveling", &texture.global_leveling, "global seam levelling");
  set.add("leveling_smoothness", &l.smoothness, "weight of smooth offsets inside patches");
  set.add("local_blending", &a.local_blending, "feather colours across seams");
  set.add("blend_width", &a.blend_width, "texels of feathering on each side of a seam");
  set.add("max_page_size", &a.max_page_size, "largest atlas page side (texels)");
  set.add("padding", &a.padding, "texels of padding around each patch");
  set.add("max_atlas_megapixels", &a.max_atlas_megapixels,
          "texel budget of the atlas (patches scaled down beyond it)");
  set.add("image_cache", &image_cache, "images kept in memory at once");
  set.add("images", &images,
          "corrected, restored (auv recon restore) or auto: restored/ when it has a water.yaml");
}

TextureStageResult runTextureStage(const Survey& survey, const TextureStageOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const fs::path mesh_file = survey.mesh() / "mesh.ply";
  const open3d::geometry::TriangleMesh input = scene::readMesh(mesh_file, "texture");
  const Survey::PinholeWorkspace workspace = survey.pinholeWorkspace();
  Survey::requireExists(workspace.model / "images.txt", "texture", "sfm");
  scene::Reconstruction model;
  try {
    model = scene::readColmapText(workspace.model);
  } catch (const std::exception& e) {
    throw StageError("texture", e.what());
  }
  if (model.images.empty()) {
    throw StageError("texture",
                     (workspace.model / "images.txt").string() + ": no registered images");
  }

  // The images: the range-aware restoration when asked for (or, with `auto`, when it was run).
  const fs::path restored = survey.root() / "restored";
  const bool use_restored = options.images == "restored" ||
                            (options.images == "auto" && fs::exists(restored / "water.yaml"));
  if (options.images == "restored")
    Survey::requireExists(restored / "water.yaml", "texture", "restore");
  const fs::path image_folder = use_restored ? restored : workspace.images;
  const std::string image_producer = use_restored ? "restore" : "correct";

  std::vector<ViewGeometry> views;
  std::vector<std::string> names;
  std::vector<fs::path> files;
  std::vector<cv::Size> sizes;
  for (const auto& [id, image] : model.images) {
    const scene::Camera& camera = model.cameraOf(image);
    if (camera.hasDistortion()) {
      throw StageError("texture", "camera " + std::to_string(camera.id) + " of " +
                                      (workspace.model / "cameras.txt").string() + " is " +
                                      scene::cameraModelName(camera.model) +
                                      " with distortion: texturing needs the undistorted "
                                      "pinhole cameras of the corrected images");
    }
    const fs::path file = image_folder / image.name;
    if (!fs::exists(file)) {
      throw StageError("texture", file.string() + ": image of " + image.name +
                                      " not found (run `auv recon " + image_producer + "` first)");
    }
    ViewGeometry view;
    view.camera = camera;
    view.world_to_camera = image.worldToCamera();
    views.push_back(view);
    names.push_back(image.name);
    files.push_back(file);
    sizes.emplace_back(camera.width, camera.height);
  }

  FaceMesh mesh;
  mesh.vertices = input.vertices_;
  mesh.faces = input.triangles_;
  mesh.computeFaceNormals(input.vertex_normals_);
  std::cerr << "texture: " << mesh.faces.size() << " faces from " << mesh_file.string() << ", "
            << views.size() << " views" << std::endl;

  ImageCache cache(files, sizes, options.image_cache);
  const ImageLoader loader = [&cache](int view) { return cv::Mat(cache.get(view)); };
  // Masks (masks/mask.h): no colour from a burned-in overlay or the vehicle's parts. Checked
  // here, so that a bad mask fails at once; read again on demand (not all held in memory).
  const masks::SurveyMasks survey_masks(survey, "texture");
  for (size_t v = 0; v < names.size(); ++v) survey_masks.forImage(names[v], sizes[v]);
  const ImageLoader mask_loader = [&](int view) {
    try {
      return survey_masks.forImage(names.at(view), sizes.at(view));
    } catch (const std::exception&) {  // checked above; never throw in the parallel loop
      return cv::Mat(sizes.at(view), CV_8U, cv::Scalar(0));  // the view gives no colour
    }
  };
  TextureResult result;
  try {
    result = textureMesh(mesh, views, loader, options.texture, mask_loader);
  } catch (const StageError& e) {
    if (!cache.errors().empty()) throw StageError("texture", cache.errors().front());
    const std::string cause = std::string(e.what()).substr(e.stage().size() + 2);
    throw StageError("texture", mesh_file.string() + ": " + cause);
  }
  const std::vector<std::string> errors = cache.errors();
  if (!errors.empty()) {
    throw StageError(
        "texture",
        errors.front() + (errors.size() > 1
                              ? " (and " + std::to_string(errors.size() - 1) + " more images)"
                              : ""));
  }

  StagedOutput staged(survey.textured());
  writeObj(result.model, staged.path(), "model");
  std::ostringstream face_views;
  face_views << "face,image\n";
  for (size_t f = 0; f < result.labels.size(); ++f) {
    face_views << f << ',' << (result.labels[f] == kNoLabel ? "" : names[result.labels[f]]) << '\n';
  }
  writeFileAtomically(staged.path() / "face_views.csv", face_views.str());
  staged.commit();

  TextureStageResult summary;
  summary.stats = result.stats;
  summary.views = views.size();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const TextureStats& s = summary.stats;
  const ViewSelectionOptions& o = options.texture.selection;
  nlohmann::json section = {
      {"input",
       {{"mesh", "mesh/mesh.ply"},
        {"sparse", "sparse/"},
        {"images", use_restored ? "restored/" : "corrected/"}}},
      {"faces", s.faces},
      {"faces_seen", s.faces_seen},
      {"faces_unseen", s.faces_unseen},
      {"views", s.views},
      {"views_used", s.views_used},
      {"observations", s.observations},
      {"observations_rejected_photo_consistency", s.rejected_observations},
      {"mrf_energy", s.energy},
      {"greedy_energy", s.greedy_energy},
      {"seams", s.seams},
      {"greedy_seams", s.greedy_seams},
      {"mrf_cycles", s.cycles},
      {"leveling_variables", s.leveling.variables},
      {"leveling_mean_jump_before", s.leveling.mean_jump_before},
      {"leveling_mean_jump_after", s.leveling.mean_jump_after},
      {"patches", s.atlas.patches},
      {"atlas_pages", s.atlas.pages},
      {"atlas_page_size", s.atlas.page_size},
      {"atlas_fill_ratio", s.atlas.fill_ratio},
      {"blended_texels", s.atlas.blended_texels},
      {"texel_scale", s.atlas.texel_scale},
      {"image_reads", cache.reads()},
      {"masked_views", survey_masks.masked()},
      {"seconds",
       {{"visibility", s.seconds_visibility},
        {"selection", s.seconds_selection},
        {"leveling", s.seconds_leveling},
        {"atlas", s.seconds_atlas},
        {"total", summary.seconds}}},
      {"options",
       {{"data_term", o.data_term},
        {"smoothness", o.smoothness},
        {"min_view_cosine", o.min_view_cosine},
        {"photo_consistency", o.photo_consistency},
        {"photo_consistency_sigma", o.photo_consistency_sigma},
        {"global_leveling", options.texture.global_leveling},
        {"local_blending", options.texture.atlas.local_blending},
        {"blend_width", options.texture.atlas.blend_width},
        {"max_page_size", options.texture.atlas.max_page_size},
        {"max_atlas_megapixels", options.texture.atlas.max_atlas_megapixels}}}};
  updateReport(survey.report(), "texture", section);
  return summary;
}

StageReport TextureStage::runWith(const Survey& survey, const TextureStageOptions& options) const {
  const TextureStageResult result = runTextureStage(survey, options);
  const auto& s = result.stats;
  std::ostringstream line;
  line << "texture: " << s.faces_seen << " of " << s.faces << " faces textured from "
       << s.views_used << " of " << result.views << " views (" << s.faces_unseen << " unseen), "
       << s.seams << " seam edges (greedy " << s.greedy_seams << "), " << s.atlas.patches
       << " patches on " << s.atlas.pages << " page(s) of " << s.atlas.page_size << " px, "
       << result.seconds << " s -> " << (survey.textured() / "model.obj").string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary = "textured model in " + survey.textured().string();
  return report;
}

}  // namespace auv::recon::texture
