#pragma once
// SIFT features of the survey's images, one binary file per image (paper section 3.4.1):
//
//   <survey>/features/
//     index.csv                 image,camera,width,height,features,file
//     <camera>/<file stem>.sift one file per image of corrected/<camera>/
//
// Image names are the SfM names: "<camera>/<file>.png" relative to corrected/.
//
// `.sift` format (little-endian, README.md of this folder):
//   char[8]  "AUVSIFT1"
//   uint32   width, height       image size, px
//   uint32   count               number of keypoints
//   uint32   descriptor_length   128
//   count x  float32 x, y, size, angle, response; uint8 r, g, b, 0   (24 bytes each)
//   count x  uint8[128]          RootSIFT descriptor, each value round(512 v) clamped to 255
//
// x, y: pixel position with pixel centres at integer coordinates (OpenCV convention) in the
// full-resolution image; size: diameter of the keypoint's neighbourhood, px (cv::KeyPoint::size);
// angle: orientation, degrees in [0, 360) (cv::KeyPoint::angle); r, g, b: colour at the keypoint.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace auv::recon::features {

struct Keypoint {
  float x = 0, y = 0;  ///< px, OpenCV convention
  float size = 0;      ///< px, neighbourhood diameter
  float angle = 0;     ///< degrees
  float response = 0;  ///< DoG contrast (larger: stronger)
  std::array<uint8_t, 3> rgb{};
};

struct ImageFeatures {
  std::string image;  ///< "<camera>/<file>.png"
  int width = 0, height = 0;
  std::vector<Keypoint> keypoints;
  cv::Mat descriptors;  ///< CV_8U, keypoints.size() x 128 (RootSIFT x 512)

  size_t size() const { return keypoints.size(); }
  /// Keypoint positions, px (for the estimators).
  std::vector<Eigen::Vector2d> positions() const;
};

/// Writes one `.sift` file atomically. Throws std::runtime_error naming the file.
void writeImageFeatures(const std::filesystem::path& file, const ImageFeatures& features);
/// Reads one `.sift` file (`image` is set by the caller / FeatureStore). Throws
/// std::runtime_error naming the file when it is missing, truncated or not a `.sift` file.
ImageFeatures readImageFeatures(const std::filesystem::path& file);

/// One line of index.csv.
struct FeatureIndexEntry {
  std::string image;   ///< "<camera>/<file>.png"
  std::string camera;  ///< its camera (the folder under corrected/)
  int width = 0, height = 0;
  size_t count = 0;            ///< keypoints
  std::filesystem::path file;  ///< relative to the features folder: "<camera>/<stem>.sift"
};

/// Writes index.csv atomically. Throws std::runtime_error naming the file.
void writeFeatureIndex(const std::filesystem::path& index_csv,
                       const std::vector<FeatureIndexEntry>& entries);

/// The features folder of a survey (`Survey::root() / "features"`), read-only.
class FeatureStore {
 public:
  /// Reads `folder`/index.csv. Throws StageError("features", ...) naming the file when the
  /// folder or index is missing (run `auv recon features` first) and std::runtime_error naming
  /// the file and line when the index is malformed.
  explicit FeatureStore(std::filesystem::path folder);

  const std::filesystem::path& folder() const { return folder_; }
  /// Images in index order (sorted by camera, then file name).
  const std::vector<FeatureIndexEntry>& images() const { return entries_; }
  bool contains(const std::string& image) const { return by_name_.count(image) > 0; }
  /// Throws std::out_of_range naming the image when it is not in the index.
  const FeatureIndexEntry& entry(const std::string& image) const;
  /// Keypoints and descriptors of one image (read from its file; not cached).
  ImageFeatures read(const std::string& image) const;

 private:
  std::filesystem::path folder_;
  std::vector<FeatureIndexEntry> entries_;
  std::map<std::string, size_t> by_name_;
};

}  // namespace auv::recon::features
