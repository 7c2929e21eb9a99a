#include "auv/recon/import/photos.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "auv/recon/common/progress.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/import/exif.h"

namespace fs = std::filesystem;

namespace auv::recon::import {
namespace {

constexpr const char* kStage = "import";

// What one readable photo is, from its first decoding; the pixels are decoded again when
// written, so that memory holds one image at a time.
struct Photo {
  fs::path file;
  ExifInfo exif;
  cv::Size upright;  ///< px, after the EXIF orientation
  std::string group;
};

bool readBytes(const fs::path& file, std::vector<unsigned char>& bytes) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

std::string groupKey(const Photo& photo) {
  std::ostringstream key;
  key << photo.upright.width << "x" << photo.upright.height;
  const std::string camera =
      photo.exif.make.empty() || photo.exif.model.rfind(photo.exif.make, 0) == 0
          ? photo.exif.model
          : photo.exif.make + " " + photo.exif.model;
  if (!camera.empty()) key << " " << camera;
  if (photo.exif.focal_mm) key << ", " << std::round(*photo.exif.focal_mm * 100.0) / 100.0 << " mm";
  return key.str();
}

// keyframes/<camera>/index.csv of imported photos (pipeline/README.md "Files").
std::string indexCsv(const std::vector<const Photo*>& photos,
                     const std::vector<std::string>& names) {
  std::ostringstream out;
  out.precision(15);
  out << "file,source,camera_time_s,sim_time_s,orientation,width,height\n";
  for (size_t i = 0; i < photos.size(); ++i) {
    const Photo& p = *photos[i];
    out << names[i] << "," << p.file.filename().string() << ",";
    if (p.exif.time_s) out << *p.exif.time_s;
    out << ",," << p.exif.orientation << "," << p.upright.width << "," << p.upright.height << "\n";
  }
  return out.str();
}

// PNG names in the camera folder: the source's stem, with its extension when two sources share
// a stem ("a.jpg" and "a.png" -> "a_jpg.png", "a_png.png").
std::vector<std::string> pngNames(const std::vector<const Photo*>& photos) {
  std::map<std::string, int> stems;
  for (const Photo* p : photos) ++stems[p->file.stem().string()];
  std::vector<std::string> names;
  for (const Photo* p : photos) {
    std::string name = p->file.stem().string();
    if (stems[name] > 1) name += "_" + p->file.extension().string().substr(1);
    names.push_back(name + ".png");
  }
  return names;
}

}  // namespace

const std::vector<std::string>& photoExtensions() {
  static const std::vector<std::string> extensions = {".jpg",  ".jpeg", ".png", ".tif",
                                                      ".tiff", ".bmp",  ".webp"};
  return extensions;
}

std::string photoDamage(const std::vector<unsigned char>& encoded, cv::Mat* decoded) {
  const size_t n = encoded.size();
  if (n == 0) return "empty file";
  // A truncated JPEG or PNG still decodes (grey or black below the cut): look for the end.
  if (n >= 2 && encoded[0] == 0xFF && encoded[1] == 0xD8) {
    size_t end = n;
    while (end > 2 && (encoded[end - 1] == 0x00 || encoded[end - 1] == 0x0A)) --end;  // padding
    if (end < 4 || encoded[end - 2] != 0xFF || encoded[end - 1] != 0xD9) {
      return "truncated JPEG (no end-of-image marker)";
    }
  }
  static const unsigned char kPng[] = {0x89, 'P', 'N', 'G'};
  if (n >= 4 && std::equal(kPng, kPng + 4, encoded.begin())) {
    static const std::string kEnd = "IEND";
    const auto tail = encoded.begin() + static_cast<long>(n > 16 ? n - 16 : 0);
    if (std::search(tail, encoded.end(), kEnd.begin(), kEnd.end()) == encoded.end()) {
      return "truncated PNG (no IEND chunk)";
    }
  }
  cv::Mat image;
  try {
    image = cv::imdecode(encoded, cv::IMREAD_COLOR | cv::IMREAD_IGNORE_ORIENTATION);
  } catch (const cv::Exception&) {
    image.release();
  }
  if (image.empty()) return "not a readable image (corrupt, or not an image OpenCV decodes)";
  if (decoded) *decoded = image;
  return {};
}

void importPhotos(const Survey& survey, const ImportStageOptions& options,
                  ImportStageResult& result) {
  const fs::path folder = options.images;
  std::error_code error;
  if (!fs::is_directory(folder, error)) {
    throw StageError(kStage, folder.string() + ": no such folder");
  }
  const std::vector<fs::path> files = listFiles(folder, photoExtensions());
  if (files.empty()) {
    throw StageError(kStage,
                     folder.string() + ": no photos (.jpg .jpeg .png .tif .tiff .bmp .webp)");
  }

  // 1. Read every file once: refuse the damaged, note size, EXIF and group.
  std::vector<Photo> photos;
  std::vector<unsigned char> bytes;
  Progress reading("import", "photos read", files.size());
  for (const fs::path& file : files) {
    cv::Mat stored;
    const std::string damage =
        readBytes(file, bytes) ? photoDamage(bytes, &stored) : "cannot be read";
    reading.advance();
    if (!damage.empty()) {
      result.skipped.push_back({file.string(), damage});
      continue;
    }
    Photo photo;
    photo.file = file;
    photo.exif = readExif(bytes);
    photo.upright =
        photo.exif.orientation >= 5 ? cv::Size(stored.rows, stored.cols) : stored.size();
    photo.group = groupKey(photo);
    photos.push_back(std::move(photo));
  }
  reading.finish();
  if (photos.empty()) {
    throw StageError(kStage, folder.string() + ": none of its " + std::to_string(files.size()) +
                                 " photos could be read (first: " + result.skipped[0].file + ": " +
                                 result.skipped[0].reason + ")");
  }

  // 2. Groups, largest first (then by key, for names that do not change between runs).
  std::map<std::string, std::vector<const Photo*>> by_group;
  for (const Photo& p : photos) by_group[p.group].push_back(&p);
  std::vector<std::pair<std::string, std::vector<const Photo*>>> groups(by_group.begin(),
                                                                        by_group.end());
  std::stable_sort(groups.begin(), groups.end(),
                   [](const auto& a, const auto& b) { return a.second.size() > b.second.size(); });
  std::string base = options.camera;
  if (base.empty()) {
    fs::path normal = fs::absolute(folder).lexically_normal();
    if (normal.filename().empty()) normal = normal.parent_path();  // "photos/" -> "photos"
    base = cameraIdFrom(normal.filename().string());
  }

  // 3. Every destination is checked before anything is written.
  std::vector<std::string> names;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::string name = g == 0 ? base : base + "-" + std::to_string(g + 1);
    if (!options.replace && fs::exists(survey.keyframes() / name, error)) {
      throw StageError(kStage, (survey.keyframes() / name).string() +
                                   " already exists: import under another --camera, or "
                                   "--replace it");
    }
    if (fs::exists(survey.recordings() / name, error)) {
      throw StageError(kStage, "camera '" + name + "' has videos in " +
                                   (survey.recordings() / name).string() +
                                   ": import the photos under another --camera");
    }
    names.push_back(name);
  }

  // 4. Write each group into its staging folder; swap them in only when all are written.
  std::vector<std::unique_ptr<StagedOutput>> outputs;
  const std::vector<int> png{cv::IMWRITE_PNG_COMPRESSION, options.png_compression};
  Progress writing("import", "photos written", photos.size());
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto& members = groups[g].second;
    outputs.push_back(std::make_unique<StagedOutput>(survey.keyframes() / names[g]));
    ImportedCamera camera;
    camera.camera = names[g];
    camera.kind = "images";
    camera.group = groups[g].first;
    const std::vector<std::string> pngs = pngNames(members);
    for (size_t i = 0; i < members.size(); ++i) {
      const Photo& p = *members[i];
      cv::Mat stored;
      if (!readBytes(p.file, bytes) || !photoDamage(bytes, &stored).empty()) {
        throw StageError(kStage, p.file.string() + ": changed while importing");
      }
      const fs::path out = outputs.back()->path() / pngs[i];
      if (!cv::imwrite(out.string(), applyOrientation(stored, p.exif.orientation), png)) {
        throw StageError(kStage, out.string() + ": cannot write");
      }
      camera.images += 1;
      camera.upright_turned += p.exif.orientation != 1;
      camera.with_time += p.exif.time_s.has_value();
      writing.advance();
    }
    writeFileAtomically(outputs.back()->path() / "index.csv", indexCsv(members, pngs));
    // One prior per group: its photos share the lens (the group key includes the focal).
    camera.prior = intrinsicsPrior(members[0]->exif, members[0]->upright, options.prior);
    camera.written = {survey.keyframes() / names[g],
                      survey.calibration() / (names[g] + ".prior.yaml")};
    result.cameras.push_back(std::move(camera));
  }
  writing.finish();
  for (auto& output : outputs) output->commit();
  for (const ImportedCamera& camera : result.cameras) {
    writeIntrinsicsPrior(camera.written[1], camera.prior);
  }
}

}  // namespace auv::recon::import
