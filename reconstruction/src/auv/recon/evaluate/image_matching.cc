#include "auv/recon/evaluate/image_matching.h"

#include <cctype>
#include <fstream>
#include <sstream>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/survey.h"

namespace fs = std::filesystem;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "evaluate";

/// One CSV line (RFC 4180 quoting: "a,b" and "" inside quotes).
std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

std::vector<KeyframeSource> readIndex(const fs::path& index, const std::string& camera) {
  std::ifstream in(index);
  if (!in) throw StageError(kStage, index.string() + ": cannot read");
  std::string line;
  if (!std::getline(in, line)) throw StageError(kStage, index.string() + ": empty (no header)");
  const std::vector<std::string> header = splitCsv(line);
  auto column = [&](const std::string& name) {
    for (size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return i;
    }
    throw StageError(kStage, index.string() + ": header has no '" + name +
                                 "' column (expected file,video,frame,...)");
  };
  const size_t file_col = column("file"), video_col = column("video"), frame_col = column("frame");
  std::vector<KeyframeSource> sources;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    const std::vector<std::string> fields = splitCsv(line);
    const size_t needed = std::max({file_col, video_col, frame_col}) + 1;
    if (fields.size() < needed) {
      throw StageError(kStage, index.string() + ":" + std::to_string(number) + ": " +
                                   std::to_string(fields.size()) + " fields, expected " +
                                   std::to_string(header.size()));
    }
    KeyframeSource source;
    source.camera = camera;
    source.file = fields[file_col];
    source.video = fields[video_col];
    try {
      size_t used = 0;
      source.frame = std::stoll(fields[frame_col], &used);
      if (used != fields[frame_col].size() || source.frame < 0) throw std::invalid_argument("");
    } catch (const std::exception&) {
      throw StageError(kStage, index.string() + ":" + std::to_string(number) + ": frame '" +
                                   fields[frame_col] + "' is not a whole number >= 0");
    }
    sources.push_back(source);
  }
  return sources;
}

}  // namespace

bool parseKeyframeName(const std::string& file, std::string& video_stem, int64_t& frame) {
  const std::string stem = fs::path(file).stem().string();
  const size_t underscore = stem.rfind('_');
  if (underscore == std::string::npos || underscore == 0 || underscore + 1 == stem.size()) {
    return false;
  }
  for (size_t i = underscore + 1; i < stem.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(stem[i]))) return false;
  }
  video_stem = stem.substr(0, underscore);
  frame = std::stoll(stem.substr(underscore + 1));
  return true;
}

std::map<std::string, std::vector<KeyframeSource>> readKeyframeSources(const fs::path& folder) {
  std::map<std::string, std::vector<KeyframeSource>> sources;
  for (const std::string& camera : Survey::cameraFolders(folder, kStage)) {
    const fs::path index = folder / camera / "index.csv";
    if (fs::exists(index)) {
      sources[camera] = readIndex(index, camera);
      continue;
    }
    std::vector<KeyframeSource>& list = sources[camera];
    for (const fs::path& file : listFiles(folder / camera, {".png", ".jpg"})) {
      KeyframeSource source;
      source.camera = camera;
      source.file = file.filename().string();
      if (parseKeyframeName(source.file, source.video, source.frame)) list.push_back(source);
    }
  }
  return sources;
}

ImageMatching matchImages(const scene::Reconstruction& reconstruction,
                          const std::map<std::string, std::vector<KeyframeSource>>& sources,
                          const GroundTruth& truth) {
  std::map<std::string, const KeyframeSource*> by_name;
  for (const auto& [camera, list] : sources) {
    for (const KeyframeSource& source : list) by_name[camera + "/" + source.file] = &source;
  }
  ImageMatching matching;
  for (const auto& [id, image] : reconstruction.images) {
    std::string key;
    const auto it = by_name.find(image.name);
    if (it != by_name.end()) {
      key = it->second->key();
    } else {
      std::string stem;
      int64_t frame = 0;
      if (parseKeyframeName(fs::path(image.name).filename().string(), stem, frame)) {
        key = frameKey(stem, frame);
      }
    }
    const GroundTruthFrame* frame = key.empty() ? nullptr : truth.find(key);
    if (frame == nullptr) {
      matching.unmatched.push_back(image.name);
      continue;
    }
    matching.matched.push_back(MatchedImage{id, image.name, frame});
  }
  return matching;
}

std::vector<PosePair> posePairs(const ImageMatching& matching,
                                const scene::Reconstruction& reconstruction) {
  std::vector<PosePair> pairs;
  for (const MatchedImage& m : matching.matched) {
    const scene::Image& image = reconstruction.images.at(m.image_id);
    PosePair pair;
    pair.name = m.name;
    pair.center_estimate = image.center();
    pair.rotation_estimate_cw = image.rotation();
    pair.center_truth = m.truth->image.center();
    pair.rotation_truth_cw = m.truth->image.rotation();
    pairs.push_back(pair);
  }
  return pairs;
}

}  // namespace auv::recon::evaluate
