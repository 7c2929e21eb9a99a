// `auv recon texture <survey>`: textured model of the trimmed mesh from the corrected images
// (src/auv/recon/texture/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/texture/texture_stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int textureMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("texture", [&] {
    texture::TextureStageOptions options;
    texture::ViewSelectionOptions& v = options.texture.selection;
    texture::SeamLevelingOptions& l = options.texture.leveling;
    texture::AtlasOptions& a = options.texture.atlas;
    std::string survey;
    OptionSet set("texture");
    set.positional("survey", &survey,
                   "survey folder (reads mesh/mesh.ply, sparse/, corrected/; writes textured/)");
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
    set.add("global_leveling", &options.texture.global_leveling, "global seam levelling");
    set.add("leveling_smoothness", &l.smoothness, "weight of smooth offsets inside patches");
    set.add("local_blending", &a.local_blending, "feather colours across seams");
    set.add("blend_width", &a.blend_width, "texels of feathering on each side of a seam");
    set.add("max_page_size", &a.max_page_size, "largest atlas page side (texels)");
    set.add("padding", &a.padding, "texels of padding around each patch");
    set.add("max_atlas_megapixels", &a.max_atlas_megapixels,
            "texel budget of the atlas (patches scaled down beyond it)");
    set.add("image_cache", &options.image_cache, "images kept in memory at once");
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const auto summary = texture::runTextureStage(Survey(survey), options);
    const auto& s = summary.stats;
    std::cout << "texture: " << s.faces_seen << " of " << s.faces << " faces textured from "
              << s.views_used << " of " << summary.views << " views (" << s.faces_unseen
              << " unseen), " << s.seams << " seam edges (greedy " << s.greedy_seams << "), "
              << s.atlas.patches << " patches on " << s.atlas.pages << " page(s) of "
              << s.atlas.page_size << " px, " << summary.seconds << " s -> "
              << (Survey(survey).textured() / "model.obj").string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("texture", 80, "<survey>   textured model (view selection, seam levelling)",
                  textureMain);

}  // namespace auv::recon
