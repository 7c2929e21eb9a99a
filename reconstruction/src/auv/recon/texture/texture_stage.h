#pragma once
// `auv recon texture`: <survey>/mesh/mesh.ply + sparse/ (posed pinhole cameras) + corrected/
// images -> <survey>/textured/model.obj, model.mtl, model_<page>.png and face_views.csv (the
// image that textures each face, for the per-camera figure); report.json section "texture".

#include <cstddef>
#include <string>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/texture/texturer.h"

namespace auv::recon::texture {

struct TextureStageOptions {
  TextureOptions texture;
  /// Images kept in memory at once (each 2704x2028 BGR is 16 MB).
  size_t image_cache = 24;
  /// Images textured from: `corrected` (lαβ, corrected/), `restored` (range-aware, restored/ of
  /// `auv recon restore`), or `auto`: restored/ when it holds a water.yaml, else corrected/.
  std::string images = "auto";

  void check() const;
  /// Binds every option to `--flag value` and to the `texture:` section of a config file.
  void bind(OptionSet& set);
};

struct TextureStageResult {
  TextureStats stats;
  size_t views = 0;
  double seconds = 0;
};

/// The whole stage. textured/ is replaced only when everything is written (StagedOutput).
/// StageError("texture", ...) naming the file for a missing mesh, sparse model or image, a
/// camera that is not pinhole, or a mesh no view sees.
TextureStageResult runTextureStage(const Survey& survey, const TextureStageOptions& options);

/// The `texture` stage (common/stage.h): `auv recon texture` and a step of `auv recon run`.
class TextureStage final : public StageWith<TextureStageOptions> {
 public:
  std::string name() const override { return "texture"; }
  std::string usage() const override {
    return "<survey>   textured model (view selection, seam levelling)";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads mesh/mesh.ply, sparse/, restored/ or corrected/; writes "
           "textured/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.mesh(), survey.sparse()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.textured()};
  }
  StageReport runWith(const Survey& survey, const TextureStageOptions& options) const override;
};

}  // namespace auv::recon::texture
