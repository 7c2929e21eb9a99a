#include "auv/recon/texture/image_cache.h"

#include <algorithm>

#include <opencv2/imgcodecs.hpp>

namespace auv::recon::texture {

ImageCache::ImageCache(std::vector<std::filesystem::path> files, std::vector<cv::Size> sizes,
                       size_t capacity)
    : files_(std::move(files)),
      sizes_(std::move(sizes)),
      capacity_(std::max<size_t>(1, capacity)) {}

cv::Mat3b ImageCache::get(int view) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = cached_.begin(); it != cached_.end(); ++it) {
      if (it->first == view) {
        cached_.splice(cached_.begin(), cached_, it);
        return it->second;
      }
    }
  }
  // Read outside the lock: two threads may read the same file once each, which is harmless.
  const std::filesystem::path& file = files_.at(static_cast<size_t>(view));
  cv::Mat image;
  std::string error;
  try {
    image = cv::imread(file.string(), cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    error = e.what();
  }
  if (image.empty()) {
    error = file.string() + ": cannot read the image" + (error.empty() ? "" : " (" + error + ")");
  } else if (image.size() != sizes_.at(static_cast<size_t>(view))) {
    error = file.string() + ": image is " + std::to_string(image.cols) + "x" +
            std::to_string(image.rows) + ", its camera " + std::to_string(sizes_[view].width) +
            "x" + std::to_string(sizes_[view].height);
    image.release();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  ++reads_;
  if (!error.empty()) {
    if (std::find(errors_.begin(), errors_.end(), error) == errors_.end()) errors_.push_back(error);
    return cv::Mat3b();
  }
  cached_.emplace_front(view, image);
  while (cached_.size() > capacity_) cached_.pop_back();
  return image;
}

std::vector<std::string> ImageCache::errors() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return errors_;
}

size_t ImageCache::reads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reads_;
}

}  // namespace auv::recon::texture
