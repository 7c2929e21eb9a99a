#include "auv/recon/change/change_map.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/staged_output.h"

namespace auv::recon::change {

namespace {
constexpr int kPixelsPerCell = 4;
constexpr int kLegendHeight = 28;
}  // namespace

Eigen::Vector3d changeColour(const M3C2Point& p, double scale_m) {
  if (!p.valid()) return Eigen::Vector3d::Constant(90.0 / 255.0);
  const double t = std::clamp(p.distance / scale_m, -1.0, 1.0);
  const double strength = std::abs(t) * (p.significant ? 1.0 : 0.25);
  const double fade = 1.0 - strength;
  return t >= 0 ? Eigen::Vector3d(1.0, fade, fade) : Eigen::Vector3d(fade, fade, 1.0);
}

void writeChangeMap(const std::filesystem::path& file,
                    const std::vector<Eigen::Vector3d>& core_points,
                    const std::vector<M3C2Point>& comparison, double cell_m, double scale_m) {
  Eigen::Vector2d low(1e300, 1e300), high(-1e300, -1e300);
  for (const Eigen::Vector3d& p : core_points) {
    low = low.cwiseMin(p.head<2>());
    high = high.cwiseMax(p.head<2>());
  }
  if (core_points.empty()) low = high = Eigen::Vector2d::Zero();
  const int rows = static_cast<int>(std::floor((high.x() - low.x()) / cell_m)) + 1;
  const int cols = static_cast<int>(std::floor((high.y() - low.y()) / cell_m)) + 1;
  // Per cell: the core point with the largest |distance| (measured ones before unmeasured).
  std::vector<int> shown(static_cast<size_t>(rows) * cols, -1);
  const auto magnitude = [&](int i) {
    const M3C2Point& p = comparison[static_cast<size_t>(i)];
    return p.valid() ? std::abs(p.distance) : -1.0;
  };
  for (size_t i = 0; i < core_points.size(); ++i) {
    const int row = static_cast<int>(std::floor((high.x() - core_points[i].x()) / cell_m));
    const int col = static_cast<int>(std::floor((core_points[i].y() - low.y()) / cell_m));
    int& cell = shown[static_cast<size_t>(row) * cols + col];
    if (cell < 0 || magnitude(static_cast<int>(i)) > magnitude(cell)) cell = static_cast<int>(i);
  }
  cv::Mat image(rows * kPixelsPerCell + kLegendHeight, cols * kPixelsPerCell, CV_8UC3,
                cv::Scalar(255, 255, 255));
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const int i = shown[static_cast<size_t>(row) * cols + col];
      if (i < 0) continue;  // no surface seen here: white
      const Eigen::Vector3d rgb = 255.0 * changeColour(comparison[static_cast<size_t>(i)], scale_m);
      const cv::Scalar colour(rgb.z(), rgb.y(), rgb.x());  // BGR
      cv::rectangle(
          image,
          cv::Rect(col * kPixelsPerCell, row * kPixelsPerCell, kPixelsPerCell, kPixelsPerCell),
          colour, cv::FILLED);
    }
  }
  std::ostringstream legend;
  legend << std::fixed << std::setprecision(2)
         << "north up; red: surface gained, blue: lost (full colour at " << scale_m
         << " m, pale: below the level of detection)";
  cv::putText(image, legend.str(), cv::Point(4, rows * kPixelsPerCell + 18),
              cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const std::filesystem::path temp = temporaryPathFor(file);
  if (!cv::imwrite(temp.string() + ".png", image)) {
    throw std::runtime_error(file.string() + ": cannot write");
  }
  std::filesystem::rename(temp.string() + ".png", file);
}

}  // namespace auv::recon::change
