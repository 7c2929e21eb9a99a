// `auv recon keyframes <survey>`: keyframe selection (paper section 3.1; keyframes/README.md).
#include <iostream>

#include "auv/recon/common/option_set.h"
#include "auv/recon/keyframes/stage.h"
#include "auv/recon/tools/command.h"

namespace auv::recon {
namespace {

int keyframesMain(const std::vector<std::string>& args) {
  return tools::runReportingErrors("keyframes", [&] {
    keyframes::KeyframeStageOptions options;
    keyframes::KeyframeOptions& s = options.selection;
    std::string survey;
    OptionSet set("keyframes");
    set.positional("survey", &survey, "survey folder (reads recordings/, writes keyframes/)");
    set.add("camera", &options.cameras, "camera id (folder of recordings/); repeatable; all");
    set.add("min_motion", &s.min_motion,
            "fraction of the image width: median feature motion for a new keyframe");
    set.add("min_tracked_fraction", &s.min_tracked_fraction,
            "new keyframe when fewer of the keyframe's features are still tracked");
    set.add("candidate_frames", &s.candidate_frames,
            "frames compared by sharpness after a trigger");
    set.add("max_candidate_frames", &s.max_candidate_frames,
            "frames a window may grow to while every candidate is refused");
    set.add("min_brightness", &s.min_brightness, "mean grey level (0-255): darker is refused");
    set.add("min_sharpness", &s.min_sharpness,
            "variance of the Laplacian below which a frame is refused as blurry");
    set.add("min_relative_sharpness", &s.min_relative_sharpness,
            "refused as blurry below this fraction of the last keyframes' median sharpness");
    set.add("sharpness_history", &s.sharpness_history, "keyframes in that median");
    set.add("min_features", &s.min_features, "corners a keyframe needs (else featureless)");
    set.add("analysis_width", &s.analysis_width,
            "px: tracking and sharpness on frames reduced to this width (0 = full size)");
    set.add("max_features", &s.max_features, "Shi-Tomasi corners per keyframe");
    set.add("feature_quality", &s.feature_quality, "corner quality (fraction of the best)");
    set.add("feature_min_distance", &s.feature_min_distance,
            "fraction of the width between corners");
    set.add("lk_window", &s.lk_window, "px (analysis resolution): Lucas-Kanade window, odd");
    set.add("lk_levels", &s.lk_levels, "Lucas-Kanade pyramid levels");
    set.add("max_fb_error", &s.max_fb_error,
            "px (analysis resolution): forward-backward tracking check (0 = off)");
    set.add("png_compression", &options.video.png_compression, "PNG compression level 0-9");
    set.add("keep_damaged", &options.video.keep_damaged,
            "keep the keyframes of a truncated/damaged video up to the damage (else an error)");
    if (!set.parse(args)) return tools::kExitOk;
    options.check();
    const keyframes::KeyframeStageResult result =
        keyframes::selectSurveyKeyframes(Survey(survey), options);
    for (const auto& camera : result.cameras) {
      std::cout << "keyframes: " << camera.camera << ": " << camera.keyframes << " keyframes of "
                << camera.frames << " frames (" << camera.videos.size() << " videos), "
                << camera.rejected << " frames refused (rejected.csv)\n";
    }
    for (const auto& problem : result.problems) {
      std::cerr << "auv recon keyframes: warning: " << problem << "\n";
    }
    std::cout << "keyframes: done in " << result.seconds << " s -> "
              << Survey(survey).keyframes().string() << std::endl;
    return tools::kExitOk;
  });
}

}  // namespace

AUV_RECON_COMMAND("keyframes", 20, "<survey>   select sharp keyframes from the recordings",
                  keyframesMain);

}  // namespace auv::recon
