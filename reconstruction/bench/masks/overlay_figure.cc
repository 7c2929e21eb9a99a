// Benchmark (issue 20 part 3, "a video with a synthetic burned-in overlay whose mask is found
// and whose model is as good as without the overlay"): the Sceaux castle photos (11, known
// focal) downscaled, with a burned-in timestamp box (its seconds change from photo to photo)
// and a vehicle part in the bottom-right corner drawn on each. The overlaid photos, in order,
// also make a video (MJPG, one frame per photo), from which `auv recon masks --detect-overlay`
// finds masks/cam.png. Then features + match + sfm, in the same run, on four surveys:
//
//   clean      the photos as taken (the anchor)
//   overlay    with the overlay, no mask
//   detected   with the overlay and the detected mask
//   true_mask  with the overlay and the exact overlay as mask (the detector's ceiling)
//
// Figures per survey: registered images, points, mean track length, mean reprojection error,
// verified matches and the fraction of them with a keypoint on the overlay (within 3 px);
// and the detected mask's IoU with the true overlay and the fraction of the scene it flags.
//
//   overlay_figure --images <sceaux_castle/images> --work DIR --out results.json [--down 4]
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/calibration/calibration.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/features/feature_store.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/features/match_store.h"
#include "auv/recon/masks/mask.h"
#include "auv/recon/overlay/masks_stage.h"
#include "auv/recon/sfm/sfm_stage.h"

namespace fs = std::filesystem;
using namespace auv::recon;

namespace {

// The overlay, in a frame of `size`: a timestamp box top-left, a part in the corner.
struct Overlay {
  cv::Rect box;
  std::vector<cv::Point> part;
};

Overlay overlayFor(cv::Size size) {
  const double s = size.width / 708.0;
  Overlay o;
  o.box = cv::Rect(static_cast<int>(10 * s), static_cast<int>(10 * s), static_cast<int>(300 * s),
                   static_cast<int>(34 * s));
  const int w = size.width - 1, h = size.height - 1;
  o.part = {{w - static_cast<int>(110 * s), h},
            {w - static_cast<int>(80 * s), h - static_cast<int>(70 * s)},
            {w, h - static_cast<int>(95 * s)},
            {w, h}};
  return o;
}

void drawOverlay(cv::Mat& image, const Overlay& o, int index) {
  const double s = image.cols / 708.0;
  image(o.box).setTo(cv::Scalar(25, 25, 25));
  char text[64];
  std::snprintf(text, sizeof text, "2026-11-27 10:41:%02d  D 12.%d m", 3 * index, index % 10);
  cv::putText(image, text, {o.box.x + static_cast<int>(6 * s), o.box.y + static_cast<int>(24 * s)},
              cv::FONT_HERSHEY_SIMPLEX, 0.6 * s, cv::Scalar(255, 255, 255), std::max(1, int(s)),
              cv::LINE_AA);
  cv::fillPoly(image, std::vector<std::vector<cv::Point>>{o.part}, cv::Scalar(70, 90, 110),
               cv::LINE_AA);
}

cv::Mat trueOverlay(cv::Size size, const Overlay& o) {
  cv::Mat truth = cv::Mat::zeros(size, CV_8U);
  truth(o.box).setTo(255);
  cv::fillPoly(truth, std::vector<std::vector<cv::Point>>{o.part}, cv::Scalar(255));
  return truth;
}

// A survey with corrected/cam/*.png and corrected/cam.yaml (pinhole, Sceaux's K scaled).
void writeSurvey(const fs::path& root, const std::vector<cv::Mat>& images,
                 const std::vector<std::string>& names, double down) {
  fs::remove_all(root);
  fs::create_directories(root / "corrected" / "cam");
  for (size_t i = 0; i < images.size(); ++i) {
    cv::imwrite((root / "corrected" / "cam" / names[i]).string(), images[i]);
  }
  calibration::CameraCalibration camera;
  camera.image_size = images[0].size();
  const double s = 1.0 / down;
  camera.camera_matrix = (cv::Mat_<double>(3, 3) << 2905.88 * s, 0, (1416 + 0.5) * s - 0.5, 0,
                          2905.88 * s, (1064 + 0.5) * s - 0.5, 0, 0, 1);
  camera.distortion = cv::Mat::zeros(1, 5, CV_64F);
  calibration::writeCalibration(root / "corrected" / "cam.yaml", camera,
                                calibration::CalibrationOptions());
}

nlohmann::json reconstruct(const fs::path& root, const cv::Mat& overlay_zone) {
  const Survey survey(root);
  const auto start = std::chrono::steady_clock::now();
  features::FeaturesStageOptions extraction;
  extraction.threads = 2;
  const auto f = features::runFeaturesStage(survey, extraction);
  features::MatchStageOptions matching;
  matching.threads = 2;
  const auto m = features::runMatchStage(survey, matching);
  // Verified matches with a keypoint on (or within 3 px of) the overlay.
  const features::FeatureStore store(root / "features");
  size_t inliers = 0, on_overlay = 0;
  for (const auto& pair :
       features::readVerifiedPairs(features::verifiedPairsFile(root / "features"))) {
    const auto a = store.read(pair.image1), b = store.read(pair.image2);
    for (const auto& [i, j] : pair.inliers) {
      const auto on = [&](const features::Keypoint& k) {
        const int u = std::clamp(static_cast<int>(std::lround(k.x)), 0, overlay_zone.cols - 1);
        const int v = std::clamp(static_cast<int>(std::lround(k.y)), 0, overlay_zone.rows - 1);
        return overlay_zone.at<uint8_t>(v, u) != 0;
      };
      ++inliers;
      on_overlay += on(a.keypoints[i]) || on(b.keypoints[j]) ? 1 : 0;
    }
  }
  nlohmann::json out = {
      {"features", f.features},
      {"masked_images", f.masked_images},
      {"verified_pairs", m.verified_pairs},
      {"verified_matches", inliers},
      {"matches_on_overlay_fraction", inliers ? static_cast<double>(on_overlay) / inliers : 0.0}};
  sfm::SfmStageOptions sfm_options;
  sfm_options.accept_partial = true;
  try {
    const auto s = sfm::runSfmStage(survey, sfm_options);
    out["registered"] = s.images_registered;
    out["images"] = s.images_total;
    out["points"] = s.points;
    out["mean_track_length"] = s.mean_track_length;
    out["mean_reprojection_error_px"] = s.mean_reprojection_error_px;
  } catch (const std::exception& e) {
    out["registered"] = 0;
    out["sfm_error"] = e.what();
  }
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path images_dir, work, out_file;
  double down = 4;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--images")
      images_dir = argv[i + 1];
    else if (flag == "--work")
      work = argv[i + 1];
    else if (flag == "--out")
      out_file = argv[i + 1];
    else if (flag == "--down")
      down = std::stod(argv[i + 1]);
    else {
      std::cerr << "overlay_figure: unknown option " << flag << "\n";
      return 2;
    }
  }
  if (images_dir.empty() || work.empty() || out_file.empty()) {
    std::cerr << "usage: overlay_figure --images DIR --work DIR --out results.json [--down 4]\n";
    return 2;
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(images_dir)) {
    if (entry.path().extension() == ".JPG" || entry.path().extension() == ".jpg") {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  std::vector<cv::Mat> clean, overlaid;
  std::vector<std::string> names;
  for (const fs::path& file : files) {
    const cv::Mat full = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (full.empty()) {
      std::cerr << "overlay_figure: " << file << ": not readable\n";
      return 1;
    }
    cv::Mat small;
    cv::resize(full, small,
               {static_cast<int>(std::lround(full.cols / down)),
                static_cast<int>(std::lround(full.rows / down))},
               0, 0, cv::INTER_AREA);
    clean.push_back(small);
    names.push_back(file.stem().string() + ".png");
  }
  if (clean.size() < 3) {
    std::cerr << "overlay_figure: fewer than 3 photos in " << images_dir << "\n";
    return 1;
  }
  const cv::Size size = clean[0].size();
  const Overlay overlay = overlayFor(size);
  for (size_t i = 0; i < clean.size(); ++i) {
    overlaid.push_back(clean[i].clone());
    drawOverlay(overlaid.back(), overlay, static_cast<int>(i));
  }
  const cv::Mat truth = trueOverlay(size, overlay);
  cv::Mat zone;  // the overlay and 3 px around it (a keypoint's support reaches beyond)
  cv::dilate(truth, zone, cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));

  nlohmann::json results = {
      {"images", clean.size()}, {"image_size", {size.width, size.height}}, {"down", down}};
  results["clean"] =
      reconstruct((writeSurvey(work / "clean", clean, names, down), work / "clean"), zone);
  writeSurvey(work / "overlay", overlaid, names, down);
  results["overlay"] = reconstruct(work / "overlay", zone);

  // The video and the detected mask.
  const fs::path detected = work / "detected";
  writeSurvey(detected, overlaid, names, down);
  fs::create_directories(detected / "recordings" / "cam");
  {
    cv::VideoWriter writer((detected / "recordings" / "cam" / "cam_0001.avi").string(),
                           cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 2, size);
    for (const cv::Mat& frame : overlaid) writer.write(frame);
  }
  overlay::MasksStageOptions mask_options;
  mask_options.detect_overlay = true;
  const auto detection = overlay::runMasksStage(Survey(detected), mask_options);
  const cv::Mat mask =
      masks::loadMask(masks::cameraMaskFile(Survey(detected), "cam"), size, "overlay_figure");
  const cv::Mat found = mask == 0;
  cv::Mat far_from_overlay;
  cv::dilate(
      truth, far_from_overlay,
      cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * mask_options.overlay.dilate_px + 9,
                                                    2 * mask_options.overlay.dilate_px + 9}));
  far_from_overlay = far_from_overlay == 0;
  results["detection"] = {
      {"frames", detection.cameras[0].detection.frames},
      {"regions", detection.cameras[0].detection.regions},
      {"masked_fraction", detection.cameras[0].detection.masked_fraction},
      {"true_overlay_covered_fraction",
       static_cast<double>(cv::countNonZero(found & truth)) / cv::countNonZero(truth)},
      {"iou_with_true_overlay",
       static_cast<double>(cv::countNonZero(found & truth)) / cv::countNonZero(found | truth)},
      {"scene_flagged_fraction", static_cast<double>(cv::countNonZero(found & far_from_overlay)) /
                                     cv::countNonZero(far_from_overlay)}};
  results["detected"] = reconstruct(detected, zone);

  writeSurvey(work / "true_mask", overlaid, names, down);
  fs::create_directories(work / "true_mask" / "masks");
  cv::Mat true_mask;
  cv::bitwise_not(truth, true_mask);
  cv::imwrite((work / "true_mask" / "masks" / "cam.png").string(), true_mask);
  results["true_mask"] = reconstruct(work / "true_mask", zone);

  fs::create_directories(out_file.parent_path().empty() ? "." : out_file.parent_path());
  std::ofstream(out_file) << results.dump(2) << "\n";
  std::cout << results.dump(2) << std::endl;
  for (const char* name : {"clean", "overlay", "detected", "true_mask"}) {
    const auto& r = results[name];
    std::cout << name << ": registered " << r.value("registered", 0) << "/" << clean.size()
              << ", points " << r.value("points", 0) << ", reprojection "
              << r.value("mean_reprojection_error_px", 0.0) << " px, matches on overlay "
              << 100 * r.value("matches_on_overlay_fraction", 0.0) << " %" << std::endl;
  }
  return 0;
}
