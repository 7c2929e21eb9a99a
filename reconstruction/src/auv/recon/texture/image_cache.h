#pragma once
// The view images for the texturing, read on demand and kept in a small least-recently-used
// cache, so that hundreds of views need not be in memory at once. Thread-safe. Reading errors
// are recorded (an empty image is returned) so that parallel loops never throw; the stage
// reports them naming the file.

#include <cstddef>
#include <filesystem>
#include <list>
#include <mutex>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace auv::recon::texture {

class ImageCache {
 public:
  /// `files[view]` is read as BGR 8-bit and must be `sizes[view]` large.
  ImageCache(std::vector<std::filesystem::path> files, std::vector<cv::Size> sizes,
             size_t capacity = 16);

  /// The image of `view`, empty when it cannot be read (see errors()).
  cv::Mat3b get(int view);
  /// One line per file that could not be read or has the wrong size.
  std::vector<std::string> errors() const;
  size_t reads() const;  ///< files read so far (cache misses)

 private:
  std::vector<std::filesystem::path> files_;
  std::vector<cv::Size> sizes_;
  size_t capacity_;
  mutable std::mutex mutex_;
  std::list<std::pair<int, cv::Mat3b>> cached_;  ///< most recent first
  std::vector<std::string> errors_;
  size_t reads_ = 0;
};

}  // namespace auv::recon::texture
