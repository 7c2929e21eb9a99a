// Fuzz harness: a recording as the reconstruction reads it: the frame-time sidecar
// `<video>.frames.csv` (keyframes::readFrameTimes; recordedSimSpan, as `figures` reads the
// survey's recordings) and the video beside it: its frame count (expectedFrameCount), its
// keyframes against its sidecar (selectVideoKeyframes) and `auv recon import` of it
// (import::importVideo, which writes a sidecar of its own that the keyframes stage must read).
// The MP4 (or other) container is opened and decoded by OpenCV's FFmpeg: the demuxer and
// decoders are the vendor's; what is fuzzed here is the project's code around them (open and
// read failures, frame counts, sizes, the sidecar's agreement with the video).
//
// A clear error is a StageError naming the file; anything else (a crash, a sanitizer report,
// another exception, or a sidecar written by the import that readFrameTimes refuses) is a bug.
//
// Input: the sidecar's bytes, then the line kVideoMarker ("\n#auv-fuzz-video\n"), then the
// video's bytes (recordings/cam/clip.mp4 of a survey in a folder of this process). Without the
// marker there is no video; an empty sidecar part means no sidecar file.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/import/video.h"
#include "auv/recon/keyframes/video.h"

namespace fs = std::filesystem;
namespace keyframes = auv::recon::keyframes;
using auv::recon::StageError;
using auv::recon::Survey;

namespace {

const std::string kVideoMarker = "\n#auv-fuzz-video\n";

fs::path folderOf(const std::string& what) {
  return fs::temp_directory_path() / ("auv_fuzz_recon_" + what + "_" + std::to_string(::getpid()));
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

struct RemoveWorkFolder {
  ~RemoveWorkFolder() {
    std::error_code ignored;
    fs::remove_all(folderOf("frames"), ignored);
  }
} remove_work_folder;

/// `auv recon import --video <video>` into a fresh survey; returns the imported video (empty
/// when the import refused it with a StageError).
fs::path importInto(const fs::path& survey, const fs::path& video) {
  fs::remove_all(survey);
  auv::recon::import::ImportStageOptions options;
  options.video = video.string();
  options.camera = "imported";
  auv::recon::import::ImportStageResult result;
  try {
    auv::recon::import::importVideo(Survey(survey), options, result);
  } catch (const StageError&) {
    return {};
  }
  return Survey(survey).recordings() / "imported" / video.filename();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const fs::path dir = folderOf("frames");
  const fs::path survey = dir / "survey", camera = Survey(survey).recordings() / "cam";
  fs::remove_all(survey);
  fs::create_directories(camera);
  const fs::path video = camera / "clip.mp4", sidecar = keyframes::sidecarOf(video);
  const size_t marker = input.find(kVideoMarker);
  const std::string sidecar_bytes = input.substr(0, marker);
  if (!sidecar_bytes.empty()) writeFile(sidecar, sidecar_bytes);
  if (marker != std::string::npos) writeFile(video, input.substr(marker + kVideoMarker.size()));

  if (!sidecar_bytes.empty()) {
    try {
      keyframes::readFrameTimes(sidecar);
    } catch (const StageError&) {
    }
  }
  double first = 0, last = 0;
  auv::recon::recordedSimSpan(Survey(survey), first, last);
  if (marker == std::string::npos) return 0;

  keyframes::expectedFrameCount(video);
  const fs::path out = dir / "keyframes";
  fs::create_directories(out);
  try {
    keyframes::selectVideoKeyframes(video, out, keyframes::KeyframeOptions{},
                                    keyframes::VideoOptions{});
  } catch (const StageError&) {
  }
  fs::remove_all(out);
  const fs::path imported = importInto(dir / "imported", video);
  if (!imported.empty()) keyframes::readFrameTimes(keyframes::sidecarOf(imported));  // must read
  return 0;
}

/// A tiny MP4 (OpenCV's VideoWriter through FFmpeg, H.264 or MPEG-4 part 2 as the simulator's
/// camera writes it) and the sidecar `auv recon import` writes for it: with both, the sidecar
/// alone, the video alone.
std::vector<std::string> auvFuzzSeeds() {
  const fs::path dir = folderOf("frames_seeds");
  fs::create_directories(dir);
  const fs::path video = dir / "clip.mp4";
  const cv::Size size(64, 48);
  cv::VideoWriter writer;
  for (const char* code : {"avc1", "mp4v"}) {
    if (writer.open(video.string(), cv::CAP_FFMPEG,
                    cv::VideoWriter::fourcc(code[0], code[1], code[2], code[3]), 10.0, size)) {
      break;
    }
  }
  if (!writer.isOpened()) throw std::runtime_error(video.string() + ": no MP4 encoder");
  cv::Mat scene(size.height, size.width + 32, CV_8UC3);
  cv::randu(scene, cv::Scalar::all(0), cv::Scalar::all(255));
  for (int i = 0; i < 6; ++i) writer.write(scene(cv::Rect(4 * i, 0, size.width, size.height)));
  writer.release();
  const fs::path imported = importInto(dir / "survey", video);
  if (imported.empty()) throw std::runtime_error(video.string() + ": the import refused it");
  const std::string sidecar = readFile(keyframes::sidecarOf(imported));
  const std::string bytes = readFile(imported);
  fs::remove_all(dir);
  return {sidecar + kVideoMarker + bytes, sidecar, kVideoMarker + bytes};
}
