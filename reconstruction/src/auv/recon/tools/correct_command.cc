// `auv recon correct <survey>`: colour correction and undistortion of the keyframes (paper
// sections 3.2 and 3.3; color/README.md).
#include <iostream>

#include "auv/recon/color/correct_stage.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int correctMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("correct", [&] {
    color::CorrectStageOptions options;
    std::string survey;
    OptionSet set("correct");
    set.positional("survey", &survey,
                   "survey folder (reads keyframes/ and calibration/, writes corrected/)");
    set.add("camera", &options.cameras, "camera id (folder of keyframes/); repeatable; all");
    set.add("undistort", &options.undistort_images,
            "undistort with calibration/<camera>.yaml (--no-undistort: keep the distortion)");
    set.add("correct_colors", &options.correct_colors,
            "lαβ colour correction (--no-correct-colors: undistortion only)");
    set.add("chroma_strength", &options.color.chroma_strength,
            "fraction of the α, β shift to the white point applied (0-1)");
    set.add("cutoff_low", &options.color.cutoff_low,
            "fraction of the pixels cut off at the dark end of the luminance");
    set.add("cutoff_high", &options.color.cutoff_high,
            "fraction of the pixels cut off at the bright end of the luminance");
    set.add("stretch_luminance", &options.color.stretch_luminance,
            "luminance cut-off and stretch (--no-stretch-luminance: off)");
    set.add("alpha", &options.undistort.alpha,
            "0: undistorted images hold valid pixels only; 1: every source pixel kept");
    set.add("png_compression", &options.png_compression, "PNG compression level 0-9");
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const color::CorrectStageResult result = color::correctSurvey(Survey(survey), options);
    for (const auto& camera : result.cameras) {
      std::cout << "correct: " << camera.camera << ": " << camera.images << " images"
                << (camera.undistorted ? ", undistorted" : ", not undistorted")
                << ", mean cast removed (alpha, beta) = (" << camera.mean_alpha << ", "
                << camera.mean_beta << ")\n";
    }
    std::cout << "correct: done in " << result.seconds << " s -> "
              << Survey(survey).corrected().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("correct", 30, "<survey>   colour-correct and undistort the keyframes",
                  correctMain);

}  // namespace auv::recon
