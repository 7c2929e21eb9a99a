#include "auv/recon/features/feature_store.h"

#include <fstream>
#include <sstream>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/features/binary_io.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr char kMagic[8] = {'A', 'U', 'V', 'S', 'I', 'F', 'T', '1'};
constexpr uint32_t kDescriptorLength = 128;
const char* kIndexHeader = "image,camera,width,height,features,file";

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

}  // namespace

namespace internal {

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return content.str();
}

}  // namespace internal

std::vector<Eigen::Vector2d> ImageFeatures::positions() const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(keypoints.size());
  for (const Keypoint& k : keypoints) out.emplace_back(k.x, k.y);
  return out;
}

void writeImageFeatures(const fs::path& file, const ImageFeatures& features) {
  const size_t count = features.keypoints.size();
  if (!features.descriptors.empty() || count > 0) {
    if (features.descriptors.type() != CV_8U ||
        features.descriptors.cols != static_cast<int>(kDescriptorLength) ||
        static_cast<size_t>(features.descriptors.rows) != count) {
      throw std::runtime_error(file.string() + ": descriptors must be " + std::to_string(count) +
                               " x 128 CV_8U");
    }
  }
  internal::ByteWriter out;
  out.putBytes(kMagic, sizeof(kMagic));
  out.put<uint32_t>(static_cast<uint32_t>(features.width));
  out.put<uint32_t>(static_cast<uint32_t>(features.height));
  out.put<uint32_t>(static_cast<uint32_t>(count));
  out.put<uint32_t>(kDescriptorLength);
  for (const Keypoint& k : features.keypoints) {
    out.put<float>(k.x);
    out.put<float>(k.y);
    out.put<float>(k.size);
    out.put<float>(k.angle);
    out.put<float>(k.response);
    out.put<uint8_t>(k.rgb[0]);
    out.put<uint8_t>(k.rgb[1]);
    out.put<uint8_t>(k.rgb[2]);
    out.put<uint8_t>(0);
  }
  for (size_t i = 0; i < count; ++i) {
    out.putBytes(features.descriptors.ptr<uint8_t>(static_cast<int>(i)), kDescriptorLength);
  }
  writeFileAtomically(file, out.bytes());
}

ImageFeatures readImageFeatures(const fs::path& file) {
  const std::string bytes = internal::readWholeFile(file.string());
  internal::ByteReader in(bytes, file.string());
  char magic[8];
  in.getBytes(magic, sizeof(magic));
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    throw std::runtime_error(file.string() + ": not a .sift feature file (bad magic)");
  }
  ImageFeatures features;
  features.width = static_cast<int>(in.get<uint32_t>());
  features.height = static_cast<int>(in.get<uint32_t>());
  const uint32_t count = in.get<uint32_t>();
  const uint32_t length = in.get<uint32_t>();
  if (length != kDescriptorLength) {
    throw std::runtime_error(file.string() + ": descriptor length " + std::to_string(length) +
                             " (expected 128)");
  }
  if (static_cast<uint64_t>(count) * (24 + length) != in.remaining()) {
    throw std::runtime_error(file.string() + ": " + std::to_string(count) +
                             " keypoints announced but " + std::to_string(in.remaining()) +
                             " bytes follow (truncated or corrupt)");
  }
  features.keypoints.resize(count);
  for (Keypoint& k : features.keypoints) {
    k.x = in.get<float>();
    k.y = in.get<float>();
    k.size = in.get<float>();
    k.angle = in.get<float>();
    k.response = in.get<float>();
    k.rgb[0] = in.get<uint8_t>();
    k.rgb[1] = in.get<uint8_t>();
    k.rgb[2] = in.get<uint8_t>();
    in.get<uint8_t>();
  }
  features.descriptors.create(static_cast<int>(count), static_cast<int>(length), CV_8U);
  if (count > 0) in.getBytes(features.descriptors.data, static_cast<size_t>(count) * length);
  return features;
}

void writeFeatureIndex(const fs::path& index_csv, const std::vector<FeatureIndexEntry>& entries) {
  std::ostringstream out;
  out << kIndexHeader << "\n";
  for (const FeatureIndexEntry& e : entries) {
    out << e.image << "," << e.camera << "," << e.width << "," << e.height << "," << e.count << ","
        << e.file.generic_string() << "\n";
  }
  writeFileAtomically(index_csv, out.str());
}

FeatureStore::FeatureStore(fs::path folder) : folder_(std::move(folder)) {
  const fs::path index = folder_ / "index.csv";
  std::error_code error;
  if (!fs::exists(index, error)) {
    throw StageError("features", index.string() + " not found (run `auv recon features` first)");
  }
  std::ifstream in(index);
  if (!in) throw std::runtime_error(index.string() + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || line != kIndexHeader) {
    throw std::runtime_error(index.string() + ": line 1: expected the header '" + kIndexHeader +
                             "'");
  }
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const std::vector<std::string> f = splitCsv(line);
    auto bad = [&](const std::string& why) {
      return std::runtime_error(index.string() + ": line " + std::to_string(line_number) + ": " +
                                why);
    };
    if (f.size() != 6) throw bad("expected 6 fields, found " + std::to_string(f.size()));
    FeatureIndexEntry entry;
    entry.image = f[0];
    entry.camera = f[1];
    try {
      entry.width = std::stoi(f[2]);
      entry.height = std::stoi(f[3]);
      entry.count = static_cast<size_t>(std::stoull(f[4]));
    } catch (const std::exception&) {
      throw bad("width, height and features must be numbers");
    }
    entry.file = f[5];
    if (by_name_.count(entry.image)) throw bad("image " + entry.image + " listed twice");
    by_name_[entry.image] = entries_.size();
    entries_.push_back(std::move(entry));
  }
}

const FeatureIndexEntry& FeatureStore::entry(const std::string& image) const {
  const auto it = by_name_.find(image);
  if (it == by_name_.end()) {
    throw std::out_of_range("features: no features for image '" + image + "' in " +
                            (folder_ / "index.csv").string());
  }
  return entries_[it->second];
}

ImageFeatures FeatureStore::read(const std::string& image) const {
  const FeatureIndexEntry& e = entry(image);
  ImageFeatures features = readImageFeatures(folder_ / e.file);
  features.image = image;
  return features;
}

}  // namespace auv::recon::features
