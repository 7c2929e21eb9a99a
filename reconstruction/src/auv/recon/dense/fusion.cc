#include "auv/recon/dense/fusion.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"

namespace auv::recon::dense {

void FusionOptions::check() const {
  AUV_RECON_CHECK_OPTION(min_consistent >= 1, min_consistent, "must be >= 1");
  AUV_RECON_CHECK_OPTION(depth_tolerance > 0 && depth_tolerance < 1, depth_tolerance,
                         "must be in (0, 1)");
  AUV_RECON_CHECK_OPTION(reprojection_px > 0, reprojection_px, "must be > 0 px");
  AUV_RECON_CHECK_OPTION(normal_step >= 1, normal_step, "must be >= 1 px");
  AUV_RECON_CHECK_OPTION(pixel_step >= 1, pixel_step, "must be >= 1 px");
}

namespace {

/// The neighbour's pixel agreeing with a master depth, or false.
bool agrees(const FusionView& master, int x, int y, const Eigen::Vector3d& world,
            const FusionView& neighbour, const FusionOptions& options, int& nx, int& ny) {
  const Eigen::Vector3d in_neighbour = neighbour.view.toCamera(world);
  if (in_neighbour.z() <= 0) return false;
  const Eigen::Vector2d pixel = neighbour.view.project(in_neighbour);
  nx = static_cast<int>(std::lround(pixel.x()));
  ny = static_cast<int>(std::lround(pixel.y()));
  if (nx < 0 || ny < 0 || nx >= neighbour.depth.cols || ny >= neighbour.depth.rows) return false;
  const double depth = neighbour.depth.at<float>(ny, nx);
  if (depth <= 0) return false;
  if (std::abs(depth - in_neighbour.z()) > options.depth_tolerance * in_neighbour.z()) {
    return false;
  }
  const Eigen::Vector3d back = neighbour.view.backProject(nx, ny, depth);
  const Eigen::Vector3d in_master = master.view.toCamera(back);
  if (in_master.z() <= 0) return false;
  return (master.view.project(in_master) - Eigen::Vector2d(x, y)).norm() <= options.reprojection_px;
}

}  // namespace

cv::Mat consistentNeighbours(const FusionView& master,
                             const std::vector<const FusionView*>& neighbours,
                             const FusionOptions& options) {
  options.check();
  cv::Mat counts(master.depth.size(), CV_8U, cv::Scalar(0));
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < master.depth.rows; ++y) {
    for (int x = 0; x < master.depth.cols; ++x) {
      const double depth = master.depth.at<float>(y, x);
      if (depth <= 0) continue;
      const Eigen::Vector3d world = master.view.backProject(x, y, depth);
      int count = 0, nx, ny;
      for (const FusionView* neighbour : neighbours) {
        if (agrees(master, x, y, world, *neighbour, options, nx, ny)) ++count;
      }
      counts.at<uint8_t>(y, x) = static_cast<uint8_t>(std::min(count, 255));
    }
  }
  return counts;
}

cv::Mat filterDepthMap(const FusionView& master, const std::vector<const FusionView*>& neighbours,
                       const FusionOptions& options) {
  const cv::Mat counts = consistentNeighbours(master, neighbours, options);
  cv::Mat filtered = master.depth.clone();
  filtered.setTo(0, counts < options.min_consistent);
  return filtered;
}

Fuser::Fuser(FusionOptions options) : options_(options) { options_.check(); }

std::vector<bool>& Fuser::used(const FusionView& view) {
  std::vector<bool>& flags = used_[view.view.image_id];
  if (flags.empty()) flags.assign(view.depth.total(), false);
  return flags;
}

FusionStats Fuser::add(const FusionView& master, const std::vector<const FusionView*>& neighbours) {
  if (master.view.color.empty() || master.view.color.size() != master.depth.size()) {
    throw std::invalid_argument("dense: fusion of " + master.view.name +
                                ": colour image missing or not of the depth map's size");
  }
  FusionStats stats;
  std::vector<bool>& master_used = used(master);
  std::vector<std::vector<bool>*> neighbour_used;
  for (const FusionView* neighbour : neighbours) neighbour_used.push_back(&used(*neighbour));
  const int cols = master.depth.cols;
  std::vector<std::pair<int, int>> hits;
  const int step = options_.pixel_step;
  for (int y = 0; y < master.depth.rows; y += step) {
    for (int x = 0; x < cols; x += step) {
      const double depth = master.depth.at<float>(y, x);
      if (depth <= 0 || master_used[static_cast<size_t>(y) * cols + x]) continue;
      ++stats.depths;
      const Eigen::Vector3d world = master.view.backProject(x, y, depth);
      hits.clear();
      std::vector<size_t> agreeing;
      for (size_t k = 0; k < neighbours.size(); ++k) {
        int nx, ny;
        if (!agrees(master, x, y, world, *neighbours[k], options_, nx, ny)) continue;
        agreeing.push_back(k);
        hits.emplace_back(nx, ny);
      }
      if (static_cast<int>(agreeing.size()) < options_.min_consistent) {
        ++stats.inconsistent;
        continue;
      }
      master_used[static_cast<size_t>(y) * cols + x] = true;
      Eigen::Vector3d position = world, normal = Eigen::Vector3d::Zero(),
                      color = Eigen::Vector3d::Zero();
      const auto addNormalAndColor = [&](const FusionView& view, int px, int py) {
        const cv::Vec3f n = view.normals.at<cv::Vec3f>(py, px);
        normal += Eigen::Vector3d(n[0], n[1], n[2]);
        const cv::Vec3b bgr = view.view.color.at<cv::Vec3b>(py, px);
        color += Eigen::Vector3d(bgr[2], bgr[1], bgr[0]);
      };
      addNormalAndColor(master, x, y);
      std::vector<uint32_t> images = {master.view.image_id};
      for (size_t i = 0; i < agreeing.size(); ++i) {
        const FusionView& neighbour = *neighbours[agreeing[i]];
        const auto [nx, ny] = hits[i];
        position += neighbour.view.backProject(nx, ny, neighbour.depth.at<float>(ny, nx));
        addNormalAndColor(neighbour, nx, ny);
        (*neighbour_used[agreeing[i]])[static_cast<size_t>(ny) * neighbour.depth.cols + nx] = true;
        images.push_back(neighbour.view.image_id);
      }
      const double n_views = 1.0 + agreeing.size();
      position /= n_views;
      if (normal.norm() < 1e-9)
        normal = master.view.center() - position;  // no normal: face the camera
      normal.normalize();
      color /= n_views;
      std::sort(images.begin(), images.end());
      images.erase(std::unique(images.begin(), images.end()), images.end());
      cloud_.positions.push_back(position.cast<float>());
      cloud_.normals.push_back(normal.cast<float>());
      cloud_.colors.push_back(color.array().round().cast<uint8_t>().matrix());
      cloud_.images.add(images);
      ++stats.points;
    }
  }
  return stats;
}

void writeFusedViews(const std::filesystem::path& file, const PointViews& images) {
  const std::filesystem::path temporary = temporaryPathFor(file);
  {
    std::ofstream out(temporary, std::ios::binary);
    const auto put = [&](auto value) {
      out.write(reinterpret_cast<const char*>(&value), sizeof(value));
    };
    put(static_cast<uint64_t>(images.size()));
    for (size_t i = 0; i < images.size(); ++i) {
      put(static_cast<uint32_t>(images.offsets[i + 1] - images.offsets[i]));
      out.write(reinterpret_cast<const char*>(images.ids.data() + images.offsets[i]),
                static_cast<std::streamsize>((images.offsets[i + 1] - images.offsets[i]) *
                                             sizeof(uint32_t)));
    }
    if (!out.flush()) {
      std::filesystem::remove(temporary);
      throw std::runtime_error("dense: cannot write " + file.string());
    }
  }
  std::filesystem::rename(temporary, file);
}

PointViews readPointViews(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("dense: cannot open " + file.string());
  const auto get = [&](auto& value) {
    if (!in.read(reinterpret_cast<char*>(&value), sizeof(value))) {
      throw std::runtime_error("dense: " + file.string() + ": truncated");
    }
  };
  uint64_t count = 0;
  get(count);
  const auto file_size = std::filesystem::file_size(file);
  if (count > file_size / 4) {
    throw std::runtime_error("dense: " + file.string() + ": malformed (claims " +
                             std::to_string(count) + " points)");
  }
  PointViews images;
  images.offsets.reserve(count + 1);
  for (uint64_t i = 0; i < count; ++i) {
    uint32_t n = 0;
    get(n);
    if (n > 100000) throw std::runtime_error("dense: " + file.string() + ": malformed entry");
    for (uint32_t j = 0; j < n; ++j) {
      uint32_t id = 0;
      get(id);
      images.ids.push_back(id);
    }
    images.offsets.push_back(images.ids.size());
  }
  return images;
}

std::vector<std::vector<uint32_t>> readFusedViews(const std::filesystem::path& file) {
  const PointViews packed = readPointViews(file);
  std::vector<std::vector<uint32_t>> images(packed.size());
  for (size_t i = 0; i < packed.size(); ++i) images[i] = packed.of(i);
  return images;
}

}  // namespace auv::recon::dense
