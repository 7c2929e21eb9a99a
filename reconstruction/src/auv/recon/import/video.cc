#include "auv/recon/import/video.h"

#include <algorithm>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/keyframes/video.h"

namespace fs = std::filesystem;

namespace auv::recon::import {
namespace {

constexpr const char* kStage = "import";

}  // namespace

void importVideo(const Survey& survey, const ImportStageOptions& options,
                 ImportStageResult& result) {
  const fs::path source = options.video;
  std::error_code error;
  if (!fs::is_regular_file(source, error)) {
    throw StageError(kStage, source.string() + ": no such video file");
  }
  std::string extension = source.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const std::vector<std::string>& containers = keyframes::videoExtensions();
  if (std::find(containers.begin(), containers.end(), extension) == containers.end()) {
    throw StageError(
        kStage, source.string() + ": not a video the keyframes stage reads (.mp4 .avi .mov .mkv)");
  }
  const std::string camera_name =
      options.camera.empty() ? cameraIdFrom(source.stem().string()) : options.camera;
  const fs::path folder = survey.recordings() / camera_name;
  const fs::path destination = folder / (source.stem().string() + extension);
  if (!options.replace && fs::exists(destination, error)) {
    throw StageError(kStage, destination.string() +
                                 " already exists: import under another --camera, or --replace it");
  }
  if (fs::exists(survey.keyframes() / camera_name / "index.csv", error) &&
      !fs::exists(folder, error)) {
    throw StageError(kStage, "camera '" + camera_name + "' holds imported photos (" +
                                 (survey.keyframes() / camera_name).string() +
                                 "): import the video under another --camera");
  }

  // Decode it once through: the frame times for the sidecar, and proof that it is a video.
  // FFmpeg, as every stage reads videos (keyframes/video.h): the same frames and times, and no
  // probing of the other backends (GStreamer's camera plugins leaked libusb's device list at
  // each open, found by the recon_frames fuzz harness under ASan).
  cv::VideoCapture capture(source.string(), cv::CAP_FFMPEG);
  std::ostringstream sidecar;
  sidecar.precision(15);
  sidecar << "frame,camera_time_s,sim_time_s\n";
  cv::Mat frame;
  int frames = 0;
  cv::Size size;
  while (capture.isOpened() && capture.read(frame) && !frame.empty()) {
    size = frame.size();
    sidecar << frames << "," << capture.get(cv::CAP_PROP_POS_MSEC) * 1e-3 << ",\n";
    ++frames;
  }
  if (frames == 0) {
    throw StageError(
        kStage, source.string() + ": cannot open the video (damaged, truncated or not a video)");
  }
  const double container_frames = capture.get(cv::CAP_PROP_FRAME_COUNT);
  if (container_frames > frames + 1) {  // counts from the container are estimates to a frame
    result.warnings.push_back(source.string() + ": the video ends after " + std::to_string(frames) +
                              " of " + std::to_string(static_cast<long>(container_frames)) +
                              " frames (damaged or truncated): imported what decodes");
  }

  // A camera's videos share one size, hence one prior.
  const fs::path prior_file = survey.calibration() / (camera_name + ".prior.yaml");
  if (fs::exists(prior_file, error) && !options.replace) {
    const IntrinsicsPrior earlier = readIntrinsicsPrior(prior_file, kStage);
    if (earlier.image_size != size) {
      throw StageError(kStage, source.string() + ": " + std::to_string(size.width) + "x" +
                                   std::to_string(size.height) + " px, but camera '" + camera_name +
                                   "' holds " + std::to_string(earlier.image_size.width) + "x" +
                                   std::to_string(earlier.image_size.height) +
                                   " px videos: import it under another --camera");
    }
  }

  // Copied under a temporary name first, so that a failed copy changes nothing; the sidecar is
  // written just before the rename that makes the video visible.
  fs::create_directories(folder, error);
  if (error) throw StageError(kStage, folder.string() + ": cannot create: " + error.message());
  const fs::path partial = temporaryPathFor(destination);
  fs::copy_file(source, partial, fs::copy_options::overwrite_existing, error);
  if (!error) {
    writeFileAtomically(keyframes::sidecarOf(destination), sidecar.str());
    fs::rename(partial, destination, error);
  }
  if (error) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw StageError(kStage, destination.string() + ": cannot write: " + error.message());
  }

  ImportedCamera camera;
  camera.camera = camera_name;
  camera.kind = "video";
  camera.frames = frames;
  camera.group = std::to_string(size.width) + "x" + std::to_string(size.height) + " video";
  camera.prior = intrinsicsPrior(ExifInfo{}, size, options.prior);
  camera.written = {destination, prior_file};
  writeIntrinsicsPrior(prior_file, camera.prior);
  result.cameras.push_back(std::move(camera));
}

}  // namespace auv::recon::import
