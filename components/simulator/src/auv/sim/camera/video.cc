#include "auv/sim/camera/video.h"

#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace auv::sim {
namespace fs = std::filesystem;

VideoRecorder::VideoRecorder(const std::string& path, double fps, cv::Size frame_size,
                             std::ostream* log)
    : path_(path), size_(frame_size) {
  if (!(fps > 0) || frame_size.width <= 0 || frame_size.height <= 0) {
    throw std::invalid_argument(path + ": bad video frame rate or size");
  }
  const fs::path final_path(path);
  if (final_path.has_parent_path()) {
    std::error_code error;
    fs::create_directories(final_path.parent_path(), error);
    if (error) {
      throw std::runtime_error(path + ": cannot create the folder: " + error.message());
    }
  }
  // Keep the .mp4 extension on the temporary name: FFmpeg picks the container from it.
  temp_path_ = (final_path.parent_path() /
                (final_path.stem().string() + ".incomplete" + final_path.extension().string()))
                   .string();
  sidecar_temp_path_ = sidecarPath(path) + ".incomplete";

  for (const char* code : {"avc1", "mp4v"}) {
    writer_.open(temp_path_, cv::CAP_FFMPEG,
                 cv::VideoWriter::fourcc(code[0], code[1], code[2], code[3]), fps, size_);
    if (writer_.isOpened()) {
      fourcc_ = code;
      break;
    }
    if (log) {
      *log << "camera: warning: " << path << ": no " << code << " encoder"
           << (std::string(code) == "avc1" ? ", falling back to mp4v (MPEG-4 part 2)" : "") << "\n";
    }
  }
  if (!writer_.isOpened()) {
    discard();
    throw std::runtime_error(path +
                             ": cannot open a video writer (no H.264 or MPEG-4 encoder "
                             "in OpenCV's FFmpeg, or the folder is not writable)");
  }
  sidecar_.open(sidecar_temp_path_);
  if (!sidecar_) {
    discard();
    throw std::runtime_error(sidecar_temp_path_ + ": cannot write the frames sidecar");
  }
  sidecar_ << "frame,camera_time_s,sim_time_s\n" << std::fixed << std::setprecision(6);
}

VideoRecorder::~VideoRecorder() {
  if (!finished_) discard();
}

void VideoRecorder::discard() noexcept {
  try {
    writer_.release();
  } catch (...) {
  }
  if (sidecar_.is_open()) sidecar_.close();
  std::error_code ignored;
  fs::remove(temp_path_, ignored);
  fs::remove(sidecar_temp_path_, ignored);
}

void VideoRecorder::write(const cv::Mat& bgr, double camera_time, double sim_time) {
  if (finished_) throw std::logic_error(path_ + ": write after finish");
  if (bgr.type() != CV_8UC3 || bgr.size() != size_) {
    throw std::invalid_argument(path_ + ": frame " + std::to_string(frames_) +
                                " is not an 8-bit BGR image of " + std::to_string(size_.width) +
                                "x" + std::to_string(size_.height));
  }
  writer_.write(bgr);
  sidecar_ << frames_ << ',' << camera_time << ',' << sim_time << '\n';
  ++frames_;
}

void VideoRecorder::finish() {
  if (finished_) return;
  writer_.release();
  sidecar_.close();
  std::error_code error;
  const auto size = fs::file_size(temp_path_, error);
  if (frames_ == 0 || error || size == 0 || !sidecar_) {
    discard();
    throw std::runtime_error(path_ + ": the encoder wrote no video (" + std::to_string(frames_) +
                             " frames given)");
  }
  // Sidecar first: a complete video never lacks its timestamps.
  fs::rename(sidecar_temp_path_, sidecarPath(path_), error);
  if (!error) fs::rename(temp_path_, path_, error);
  if (error) {
    discard();
    throw std::runtime_error(path_ +
                             ": cannot move the finished video into place: " + error.message());
  }
  finished_ = true;
}

std::vector<FrameStamp> readFrameSidecar(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the frames sidecar");
  std::vector<FrameStamp> rows;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line_number == 1) {
      if (line.rfind("frame,camera_time_s,sim_time_s", 0) != 0) {
        throw std::runtime_error(path + ":1: expected the header frame,camera_time_s,sim_time_s");
      }
      continue;
    }
    if (line.empty()) continue;
    std::istringstream fields(line);
    FrameStamp row;
    char comma1 = 0, comma2 = 0;
    if (!(fields >> row.frame >> comma1 >> row.camera_time >> comma2 >> row.sim_time) ||
        comma1 != ',' || comma2 != ',') {
      throw std::runtime_error(path + ":" + std::to_string(line_number) +
                               ": expected frame,camera_time_s,sim_time_s");
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace auv::sim
