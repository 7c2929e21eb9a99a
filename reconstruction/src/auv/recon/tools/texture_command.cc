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
    std::string survey;
    OptionSet set("texture");
    set.positional("survey", &survey,
                   "survey folder (reads mesh/mesh.ply, sparse/, corrected/; writes textured/)");
    options.bind(set);
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
