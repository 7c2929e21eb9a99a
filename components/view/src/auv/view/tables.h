#pragma once
// The run folder's CSV and TUM files (components/mission/README.md "Mission log and report",
// components/simulator/README.md "Run folder"), read by column name so added columns do not
// break the viewer. A malformed number is a ConfigError naming file, line and column.

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace auv::view {

/// The named numeric columns of a CSV with a header line, in that order. Throws
/// config::ConfigError naming the file for a missing column and file:line for a bad number.
std::vector<std::vector<double>> readCsvColumns(const std::filesystem::path& file,
                                                const std::vector<std::string>& columns);

struct StampedPosition {
  double t = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};
/// "t x y z qx qy qz qw" lines ('#' comments skipped); ConfigError naming file:line.
std::vector<StampedPosition> readTum(const std::filesystem::path& file);

/// Polylines as the page draws them: xyz of every vertex, and per line its first vertex and
/// vertex count ("starts", "counts").
struct Polylines {
  std::vector<float> xyz;
  std::vector<uint32_t> starts, counts;
  void add(const std::vector<Eigen::Vector3d>& points);
  size_t lines() const { return starts.size(); }
};

}  // namespace auv::view
