#include "auv/view/tables.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "auv/config/errors.h"

namespace auv::view {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::string field;
  std::stringstream stream(line);
  if (separator == ' ') {
    while (stream >> field) fields.push_back(field);
  } else {
    while (std::getline(stream, field, separator)) fields.push_back(field);
  }
  return fields;
}

double parseNumber(const std::string& text, const fs::path& file, size_t line,
                   const std::string& column) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  while (end && (*end == ' ' || *end == '\r')) ++end;
  if (text.empty() || end == begin || *end != '\0') {
    throw config::ConfigError(file.string() + ":" + std::to_string(line) + ": " + column +
                              ": expected a number, got '" + text + "'");
  }
  return value;
}

}  // namespace

std::vector<std::vector<double>> readCsvColumns(const fs::path& file,
                                                const std::vector<std::string>& columns) {
  std::ifstream in(file);
  if (!in) throw config::ConfigError(file.string() + ": cannot read");
  std::string line;
  if (!std::getline(in, line)) return {};
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line, ',');
  std::vector<size_t> index;
  for (const auto& name : columns) {
    size_t i = 0;
    while (i < header.size() && header[i] != name) ++i;
    if (i == header.size()) {
      throw config::ConfigError(file.string() + ": no column '" + name + "' in the header '" +
                                line + "'");
    }
    index.push_back(i);
  }
  std::vector<std::vector<double>> rows;
  size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    const std::vector<std::string> fields = split(line, ',');
    std::vector<double> row;
    for (size_t c = 0; c < index.size(); ++c) {
      if (index[c] >= fields.size()) {
        throw config::ConfigError(file.string() + ":" + std::to_string(number) + ": " + columns[c] +
                                  ": missing (line has " + std::to_string(fields.size()) +
                                  " fields)");
      }
      row.push_back(parseNumber(fields[index[c]], file, number, columns[c]));
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<StampedPosition> readTum(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw config::ConfigError(file.string() + ": cannot read");
  std::vector<StampedPosition> poses;
  std::string line;
  size_t number = 0;
  static const char* kNames[] = {"t", "x", "y", "z"};
  while (std::getline(in, line)) {
    ++number;
    const std::vector<std::string> fields = split(line, ' ');
    if (fields.empty() || fields[0][0] == '#') continue;
    if (fields.size() < 4) {
      throw config::ConfigError(file.string() + ":" + std::to_string(number) +
                                ": expected 't x y z qx qy qz qw', got '" + line + "'");
    }
    double v[4];
    for (int i = 0; i < 4; ++i) v[i] = parseNumber(fields[i], file, number, kNames[i]);
    poses.push_back({v[0], {v[1], v[2], v[3]}});
  }
  return poses;
}

void Polylines::add(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return;
  starts.push_back(static_cast<uint32_t>(xyz.size() / 3));
  counts.push_back(static_cast<uint32_t>(points.size()));
  for (const auto& p : points) {
    xyz.push_back(static_cast<float>(p.x()));
    xyz.push_back(static_cast<float>(p.y()));
    xyz.push_back(static_cast<float>(p.z()));
  }
}

}  // namespace auv::view
