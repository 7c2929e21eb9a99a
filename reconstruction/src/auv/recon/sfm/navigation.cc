#include "auv/recon/sfm/navigation.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auv::recon::sfm {

std::map<std::string, double> readKeyframeTimes(const std::filesystem::path& keyframes_folder,
                                                const std::vector<std::string>& cameras) {
  std::map<std::string, double> times;
  for (const std::string& camera : cameras) {
    const std::filesystem::path index = keyframes_folder / camera / "index.csv";
    std::ifstream in(index);
    if (!in) continue;
    std::string line;
    std::getline(in, line);
    // Columns by name: file and sim_time_s.
    std::vector<std::string> header;
    {
      std::istringstream h(line);
      std::string cell;
      while (std::getline(h, cell, ',')) {
        if (!cell.empty() && cell.back() == '\r') cell.pop_back();
        header.push_back(cell);
      }
    }
    const auto file_column = std::find(header.begin(), header.end(), "file");
    const auto time_column = std::find(header.begin(), header.end(), "sim_time_s");
    if (file_column == header.end() || time_column == header.end()) {
      throw std::runtime_error(index.string() + ":1: header has no 'file' or 'sim_time_s'");
    }
    const size_t fc = file_column - header.begin(), tc = time_column - header.begin();
    for (size_t number = 2; std::getline(in, line); ++number) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty()) continue;
      std::vector<std::string> cells;
      std::istringstream l(line);
      std::string cell;
      while (std::getline(l, cell, ',')) cells.push_back(cell);
      if (line.back() == ',') cells.emplace_back();
      if (cells.size() <= std::max(fc, tc)) {
        throw std::runtime_error(index.string() + ":" + std::to_string(number) +
                                 ": fewer columns than the header");
      }
      if (cells[tc].empty()) continue;
      try {
        size_t used = 0;
        const double t = std::stod(cells[tc], &used);
        if (used != cells[tc].size() || !std::isfinite(t)) throw std::invalid_argument("");
        times[camera + "/" + cells[fc]] = t;
      } catch (const std::exception&) {
        throw std::runtime_error(index.string() + ":" + std::to_string(number) + ": sim_time_s '" +
                                 cells[tc] + "' is not a number");
      }
    }
  }
  return times;
}

NavigationAlignment alignToNavigation(scene::Reconstruction& reconstruction,
                                      const std::map<std::string, double>& image_times,
                                      const std::vector<TimedPosition>& trajectory,
                                      size_t min_images) {
  NavigationAlignment result;
  std::vector<Eigen::Vector3d> from, to;
  for (const auto& [id, image] : reconstruction.images) {
    auto t = image_times.find(image.name);
    Eigen::Vector3d position;
    if (t == image_times.end() || !positionAt(trajectory, t->second, position)) continue;
    from.push_back(image.center());
    to.push_back(position);
  }
  result.images = from.size();
  if (from.size() < std::max<size_t>(min_images, 3)) {
    result.reason = std::to_string(from.size()) +
                    " registered images have a navigation position (needs " +
                    std::to_string(std::max<size_t>(min_images, 3)) + ")";
    return result;
  }
  const std::optional<Similarity> s = estimateSimilarity(from, to);
  if (!s) {
    result.reason = "the camera centres are collinear: the rotation about their line is free";
    return result;
  }
  double sum = 0;
  for (size_t i = 0; i < from.size(); ++i) sum += (s->apply(from[i]) - to[i]).squaredNorm();
  result.rms_m = std::sqrt(sum / from.size());
  transformReconstruction(*s, reconstruction);
  result.similarity = *s;
  result.applied = true;
  return result;
}

}  // namespace auv::recon::sfm
