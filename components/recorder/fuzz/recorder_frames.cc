// Fuzz harness: a recording as the recorder catalogues it on the vehicle: the frame-time sidecar
// `<video>.frames.csv` the camera driver (or the simulator) writes beside each video, read
// closed and while being written (readSidecarSummary), and the recording with its sidecar as a
// scan finds it (Catalogue::scan: the sidecar's summary, the video's and sidecar's digests).
// The recorder opens no video container: it only hashes the bytes (the MP4 is parsed by the
// reconstruction, reconstruction/fuzz/recon_frames.cc, with the same input layout). A clear error is
// a std::runtime_error naming the file (readSidecarSummary; a scan reports problems and never
// throws); anything else (a crash, a sanitizer report, another exception) is a bug.
//
// Input: the sidecar's bytes, then the line kVideoMarker ("\n#auv-fuzz-video\n"), then the
// video's bytes. Without the marker the video is empty; an empty sidecar part means no sidecar.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/recorder/catalogue.h"

namespace fs = std::filesystem;

namespace {

const std::string kVideoMarker = "\n#auv-fuzz-video\n";

fs::path workFolder() {
  return fs::temp_directory_path() / ("auv_fuzz_recorder_frames_" + std::to_string(::getpid()));
}

struct RemoveWorkFolder {
  ~RemoveWorkFolder() {
    std::error_code ignored;
    fs::remove_all(workFolder(), ignored);
  }
} remove_work_folder;

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

/// A sidecar as the simulator's VideoRecorder writes it (components/simulator camera/video.cc:
/// std::fixed, 6 decimals; sim_time_s empty from a real camera); `last_line`: the unterminated
/// row of a sidecar still being written.
std::string sidecar(int frames, bool sim_time, const std::string& last_line = "") {
  std::string text = "frame,camera_time_s,sim_time_s\n";
  char row[96];
  for (int i = 0; i < frames; ++i) {
    if (sim_time) {
      std::snprintf(row, sizeof row, "%d,%.6f,%.6f\n", i, 37.4 + 0.1 * i, 0.1 * i);
    } else {
      std::snprintf(row, sizeof row, "%d,%.6f,\n", i, 37.4 + 0.1 * i);
    }
    text += row;
  }
  return text + last_line;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t marker = input.find(kVideoMarker);
  const std::string sidecar_bytes = input.substr(0, marker);
  const std::string video_bytes =
      marker == std::string::npos ? "" : input.substr(marker + kVideoMarker.size());
  const fs::path root = workFolder() / "root", camera = root / "cam";
  fs::remove_all(root);
  fs::create_directories(camera);
  const fs::path video = camera / "cam_0001.mp4", sidecar_file = camera / "cam_0001.mp4.frames.csv";
  writeFile(video, video_bytes);
  if (!sidecar_bytes.empty()) {
    writeFile(sidecar_file, sidecar_bytes);
    for (const bool partial : {false, true}) {
      try {
        auv::recorder::readSidecarSummary(sidecar_file, partial);
      } catch (const std::runtime_error&) {
      }
    }
  }
  auv::recorder::CatalogueOptions options;
  options.root = root;
  options.chunk_digest_bytes = 64;
  auv::recorder::Catalogue catalogue(options);
  catalogue.scan();
  catalogue.list("", true);
  return 0;
}

/// Sidecars in the format the cameras write (with and without sim_time_s, closed and being
/// written) beside a few bytes of video (only hashed here). The recorder has no writer of its
/// own and does not link the simulator's VideoRecorder, so they are made here in its format.
std::vector<std::string> auvFuzzSeeds() {
  const std::string video = std::string(
      "\0\0\0\x18"
      "ftypisom\0\0\x02\0isomiso2",
      24);
  return {sidecar(5, true) + kVideoMarker + video, sidecar(3, false) + kVideoMarker + video,
          sidecar(2, true, "2,37.6"), kVideoMarker + video};
}
