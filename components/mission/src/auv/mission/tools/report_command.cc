// `auv mission report <run-dir>`: the mission figure (top-down SVG: map, planner trees and
// paths, true and estimated trajectories, waypoints, collisions) and summary.json, from the
// simulator's ground truth and the mission handler's log (components/mission/README.md).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>
#include <Eigen/Core>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/mission/tools/mission_cli.h"

namespace auv::mission {
namespace {
namespace fs = std::filesystem;

struct Sample {
  double t;
  Eigen::Vector3d p;
};

/// Rows of a CSV (header skipped) or whitespace table ('#' comments skipped) as strings.
std::vector<std::vector<std::string>> readTable(const fs::path& path, char separator,
                                                bool has_header) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (first && has_header) {
      first = false;
      continue;
    }
    first = false;
    std::vector<std::string> fields;
    std::stringstream stream(line);
    std::string field;
    if (separator == ' ') {
      while (stream >> field) fields.push_back(field);
    } else {
      while (std::getline(stream, field, separator)) fields.push_back(field);
    }
    rows.push_back(fields);
  }
  return rows;
}

double number(const std::string& text) {
  try {
    return std::stod(text);
  } catch (const std::exception&) {
    return std::nan("");
  }
}

std::vector<Sample> readTum(const fs::path& path) {
  std::vector<Sample> samples;
  for (const auto& row : readTable(path, ' ', false)) {
    if (row.size() < 4) continue;
    samples.push_back({number(row[0]), {number(row[1]), number(row[2]), number(row[3])}});
  }
  return samples;
}

double pathLength(const std::vector<Sample>& samples, double from, double to) {
  double length = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i - 1].t < from || samples[i].t > to) continue;
    length += (samples[i].p - samples[i - 1].p).norm();
  }
  return length;
}

const Sample* at(const std::vector<Sample>& samples, double t) {
  auto it = std::lower_bound(samples.begin(), samples.end(), t,
                             [](const Sample& s, double time) { return s.t < time; });
  if (it == samples.end()) return samples.empty() ? nullptr : &samples.back();
  return &*it;
}

std::string json(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

std::string quote(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

/// Top-down figure drawn twice, as SVG (vector, for papers) and PNG (OpenCV, for quick looks):
/// north up (x NED), east right (y NED). Colours are "#rrggbb".
class Figure {
 public:
  static constexpr int kLegendHeight = 60;

  Figure(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double pixels_per_metre)
      : min_(min), max_(max), scale_(pixels_per_metre) {
    width_ = (max.y() - min.y()) * scale_;
    height_ = (max.x() - min.x()) * scale_;
    svg_ << "<svg xmlns='http://www.w3.org/2000/svg' width='" << width_ << "' height='"
         << height_ + kLegendHeight << "' font-family='sans-serif' font-size='12'>\n"
         << "<rect width='100%' height='100%' fill='white'/>\n";
    png_ = cv::Mat(static_cast<int>(std::ceil(height_)) + kLegendHeight,
                   static_cast<int>(std::ceil(width_)), CV_8UC3, cv::Scalar(255, 255, 255));
  }
  double x(const Eigen::Vector3d& p) const { return (p.y() - min_.y()) * scale_; }
  double y(const Eigen::Vector3d& p) const { return (max_.x() - p.x()) * scale_; }
  double height() const { return height_; }

  void polyline(const std::vector<Eigen::Vector3d>& points, const std::string& colour, double width,
                bool dashed = false) {
    if (points.size() < 2) return;
    svg_ << "<polyline fill='none' stroke='" << colour << "' stroke-width='" << width << "'"
         << (dashed ? " stroke-dasharray='4,3'" : "") << " points='";
    for (const auto& p : points) svg_ << x(p) << "," << y(p) << " ";
    svg_ << "'/>\n";
    for (std::size_t i = 1; i < points.size(); ++i) {
      if (dashed && i % 2 == 0) continue;
      cv::line(png_, pixel(points[i - 1]), pixel(points[i]), bgr(colour),
               std::max(1, static_cast<int>(std::lround(width))), cv::LINE_AA);
    }
  }
  void square(const Eigen::Vector3d& centre, double size, const std::string& colour) {
    const double half = size * scale_ / 2;
    svg_ << "<rect x='" << x(centre) - half << "' y='" << y(centre) - half << "' width='"
         << 2 * half << "' height='" << 2 * half << "' fill='" << colour << "'/>\n";
    cv::rectangle(png_, cv::Point2d(x(centre) - half, y(centre) - half),
                  cv::Point2d(x(centre) + half, y(centre) + half), bgr(colour), cv::FILLED);
  }
  void circle(const Eigen::Vector3d& c, double radius, const std::string& colour, bool filled) {
    svg_ << "<circle cx='" << x(c) << "' cy='" << y(c) << "' r='" << radius << "' "
         << (filled ? "fill='" + colour + "'"
                    : "fill='none' stroke='" + colour + "' stroke-width='2'")
         << "/>\n";
    cv::circle(png_, pixel(c), static_cast<int>(std::lround(radius)), bgr(colour),
               filled ? cv::FILLED : 2, cv::LINE_AA);
  }
  void text(double px, double py, const std::string& text, const std::string& colour) {
    svg_ << "<text x='" << px << "' y='" << py << "' fill='" << colour << "'>" << text
         << "</text>\n";
    cv::putText(png_, text, cv::Point2d(px, py), cv::FONT_HERSHEY_SIMPLEX, 0.4, bgr(colour), 1,
                cv::LINE_AA);
  }
  /// Writes <stem>.svg and <stem>.png; false when either could not be written.
  bool write(const fs::path& stem) {
    std::ofstream svg(stem.string() + ".svg");
    svg << svg_.str() << "</svg>\n";
    return static_cast<bool>(svg) && cv::imwrite(stem.string() + ".png", png_);
  }

 private:
  cv::Point pixel(const Eigen::Vector3d& p) const {
    return {static_cast<int>(std::lround(x(p))), static_cast<int>(std::lround(y(p)))};
  }
  static cv::Scalar bgr(const std::string& hex) {
    const unsigned value = static_cast<unsigned>(std::stoul(hex.substr(1), nullptr, 16));
    return cv::Scalar(value & 0xff, (value >> 8) & 0xff, (value >> 16) & 0xff);
  }
  Eigen::Vector2d min_, max_;
  double scale_, width_, height_;
  std::ostringstream svg_;
  cv::Mat png_;
};

struct QueryRecord {
  int index = -1;
  double start_t = std::nan(""), end_t = std::nan("");
  Eigen::Vector3d start = Eigen::Vector3d::Constant(std::nan(""));
  Eigen::Vector3d end = Eigen::Vector3d::Constant(std::nan(""));
  bool succeeded = false;
  bool interrupted = false;  // a safety manoeuvre ended this attempt (the query was re-issued)
};

/// What the mission log says: the queries in order, the waypoints and how the mission ended.
struct MissionRecord {
  std::map<std::string, QueryRecord> queries;  // by query id
  std::vector<QueryRecord*> ordered;           // by start time
  std::vector<Eigen::Vector3d> waypoints;
  std::string final_state = "UNKNOWN", final_message;
  double start = std::nan(""), end = std::nan("");
  std::map<int, int> recoveries;                 // by query index (RECOVERY_START events)
  std::vector<Eigen::Vector3d> recovery_points;  // where each began
};

/// Reads events.csv and waypoints.csv; a query ends where the next starts, or at the end.
void readMissionLog(const fs::path& log, const std::vector<Sample>& truth, MissionRecord& m) {
  for (const auto& row : readTable(log / "events.csv", ',', true)) {
    if (row.size() < 9) continue;
    const double t = number(row[0]);
    const std::string state = row[1].substr(0, row[1].find('/'));
    const Eigen::Vector3d position(number(row[5]), number(row[6]), number(row[7]));
    if (std::isnan(m.start)) m.start = t;
    m.end = t;
    const std::string query_id = row[3];
    if (row[1] == "RECOVERY_START") {
      ++m.recoveries[std::stoi(row[2])];
      m.recovery_points.push_back(position);
      m.queries[query_id].interrupted = true;
      continue;
    }
    if (row[1].find('/') == std::string::npos) continue;  // other named events
    m.final_state = state;
    m.final_message = row[8];
    if (query_id != "0") {
      QueryRecord& q = m.queries[query_id];
      if (std::isnan(q.start_t)) {
        q.start_t = t;
        q.start = position;
        q.index = std::stoi(row[2]);
      }
    }
  }
  for (const auto& row : readTable(log / "waypoints.csv", ',', true)) {
    if (row.size() >= 6) m.waypoints.push_back({number(row[3]), number(row[4]), number(row[5])});
  }
  for (auto& [id, q] : m.queries) m.ordered.push_back(&q);
  std::sort(m.ordered.begin(), m.ordered.end(),
            [](const QueryRecord* a, const QueryRecord* b) { return a->start_t < b->start_t; });
  for (std::size_t i = 0; i < m.ordered.size(); ++i) {
    QueryRecord& q = *m.ordered[i];
    q.end_t = i + 1 < m.ordered.size() ? m.ordered[i + 1]->start_t : m.end;
    q.succeeded = !q.interrupted && (i + 1 < m.ordered.size() || m.final_state == "SUCCEEDED");
    if (const Sample* s = at(truth, q.end_t)) q.end = s->p;
    if (const Sample* s = at(truth, q.start_t)) q.start = s->p;
  }
}

/// What the simulator's ground truth says of the mission's span.
struct TruthFacts {
  std::vector<Eigen::Vector3d> collisions;
  double min_clearance = std::numeric_limits<double>::infinity();
  double max_nav_error = 0.0;
};

TruthFacts readTruthFacts(const fs::path& run, const std::vector<Sample>& truth,
                          const std::vector<Sample>& estimate, const MissionRecord& m) {
  TruthFacts facts;
  for (const auto& row : readTable(run / "ground_truth" / "collisions.csv", ',', true)) {
    if (row.size() >= 10 && row[9] == "1") {
      facts.collisions.push_back({number(row[1]), number(row[2]), number(row[3])});
    }
  }
  for (const auto& row : readTable(run / "ground_truth" / "clearance.csv", ',', true)) {
    if (row.size() >= 2) {
      const double t = number(row[0]);
      if (t >= m.start && t <= m.end)
        facts.min_clearance = std::min(facts.min_clearance, number(row[1]));
    }
  }
  for (const Sample& s : estimate) {
    if (s.t < m.start || s.t > m.end) continue;
    if (const Sample* true_sample = at(truth, s.t)) {
      facts.max_nav_error = std::max(facts.max_nav_error, (true_sample->p - s.p).head<2>().norm());
    }
  }
  return facts;
}

/// The mapped occupied columns (0.5 m, top-down) of the mission's map.bt, if any.
std::set<std::pair<int, int>> occupiedColumns(const fs::path& map_file, double column) {
  std::set<std::pair<int, int>> columns;
  if (!fs::exists(map_file)) return columns;
  octomap::OcTree map(0.1);
  if (!map.readBinary(map_file.string())) return columns;
  for (auto it = map.begin_leafs(); it != map.end_leafs(); ++it) {
    if (!map.isNodeOccupied(*it)) continue;
    columns.insert({static_cast<int>(std::floor(it.getX() / column)),
                    static_cast<int>(std::floor(it.getY() / column))});
  }
  return columns;
}

/// Planner trees (the last of each query) as thin lines.
void drawTrees(Figure& figure, const fs::path& log) {
  for (const auto& entry : fs::directory_iterator(log)) {
    if (entry.path().filename().string().rfind("tree_", 0) != 0) continue;
    const auto rows = readTable(entry.path(), ',', true);
    std::vector<Eigen::Vector3d> nodes;
    for (const auto& row : rows) nodes.push_back({number(row[2]), number(row[3]), number(row[4])});
    for (const auto& row : rows) {
      const int parent = static_cast<int>(number(row[1]));
      const int index = static_cast<int>(number(row[0]));
      if (parent >= 0 && parent < static_cast<int>(nodes.size())) {
        figure.polyline({nodes[parent], nodes[index]}, "#d6e1ef", 0.6);
      }
    }
  }
}

/// The last planner path of each query.
void drawPaths(Figure& figure, const fs::path& log) {
  std::map<std::string, std::vector<Eigen::Vector3d>> paths;
  std::map<std::string, std::string> last_seq;
  for (const auto& row : readTable(log / "paths.csv", ',', true)) {
    if (row.size() < 7) continue;
    if (last_seq[row[1]] != row[2]) {
      paths[row[1]].clear();
      last_seq[row[1]] = row[2];
    }
    paths[row[1]].push_back({number(row[4]), number(row[5]), number(row[6])});
  }
  for (const auto& [id, path] : paths) figure.polyline(path, "#2e8b57", 1.5, true);
}

void drawLegend(Figure& figure, const MissionRecord& m, const TruthFacts& facts, double scale) {
  const double legend = figure.height() + 18;
  figure.text(10, legend, "true trajectory", "#1f4e9c");
  figure.text(120, legend, "navigation estimate", "#ff8c00");
  figure.text(260, legend, "last planner paths", "#2e8b57");
  figure.text(390, legend, "planner trees", "#7a9cc6");
  figure.text(490, legend, "mapped occupied (top-down)", "#9a8c7a");
  figure.text(10, legend + 18,
              m.final_state + " - collisions: " + std::to_string(facts.collisions.size()) +
                  " - recoveries (R): " + std::to_string(m.recovery_points.size()) +
                  " - north up, east right, " + json(1.0 / scale * 100) + " m per 100 px",
              facts.collisions.empty() ? "#000000" : "#ff0000");
}

std::string summaryJson(const fs::path& run, const MissionRecord& m, const TruthFacts& facts,
                        const std::vector<Sample>& truth) {
  std::ostringstream summary;
  summary << "{\n  \"run\": " << quote(fs::absolute(run).string()) << ",\n"
          << "  \"state\": " << quote(m.final_state) << ",\n"
          << "  \"message\": " << quote(m.final_message) << ",\n"
          << "  \"duration_s\": " << json(m.end - m.start) << ",\n"
          << "  \"collisions\": " << facts.collisions.size() << ",\n"
          << "  \"min_true_clearance_m\": " << json(facts.min_clearance) << ",\n"
          << "  \"max_navigation_error_m\": " << json(facts.max_nav_error) << ",\n"
          << "  \"executed_length_m\": " << json(pathLength(truth, m.start, m.end)) << ",\n";
  int recoveries = 0;
  for (const auto& [index, count] : m.recoveries) recoveries += count;
  summary << "  \"recoveries\": " << recoveries << ",\n  \"queries\": [";
  for (std::size_t i = 0; i < m.ordered.size(); ++i) {
    const QueryRecord& q = *m.ordered[i];
    summary << (i ? "," : "") << "\n    {\"index\": " << q.index
            << ", \"succeeded\": " << (q.succeeded ? "true" : "false")
            << ", \"interrupted\": " << (q.interrupted ? "true" : "false")
            << ", \"recoveries\": " << (m.recoveries.count(q.index) ? m.recoveries.at(q.index) : 0)
            << ", \"start_t\": " << json(q.start_t) << ", \"end_t\": " << json(q.end_t)
            << ", \"start\": [" << json(q.start.x()) << ", " << json(q.start.y()) << ", "
            << json(q.start.z()) << "], \"end\": [" << json(q.end.x()) << ", " << json(q.end.y())
            << ", " << json(q.end.z())
            << "], \"executed_length_m\": " << json(pathLength(truth, q.start_t, q.end_t)) << "}";
  }
  summary << "\n  ]\n}\n";
  return summary.str();
}

}  // namespace

int reportMain(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help") {
    std::cerr << "usage: auv mission report <run-dir> [--out DIR]\n";
    return args.empty() ? 2 : 0;
  }
  const fs::path run = args[0];
  const fs::path log = run / "mission";
  fs::path out_dir = log;
  if (args.size() == 3 && args[1] == "--out") {
    out_dir = args[2];
  } else if (args.size() != 1) {
    std::cerr << "auv mission report: usage: auv mission report <run-dir> [--out DIR]\n";
    return 2;
  }
  for (const fs::path& needed : {log / "events.csv", run / "ground_truth" / "trajectory.tum"}) {
    if (!fs::exists(needed)) {
      std::cerr << "auv mission report: " << needed.string()
                << " is missing (a run folder of `auv launch bringup/launch/vehicle.yaml`?)\n";
      return 1;
    }
  }
  const auto truth = readTum(run / "ground_truth" / "trajectory.tum");
  const auto estimate = readTum(run / "ground_truth" / "navigation.tum");
  MissionRecord mission;
  readMissionLog(log, truth, mission);
  const TruthFacts facts = readTruthFacts(run, truth, estimate, mission);

  // Figure extent: trajectories and map.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e9), hi = Eigen::Vector2d::Constant(-1e9);
  auto grow = [&](const Eigen::Vector3d& p) {
    if (!p.allFinite()) return;
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  };
  for (const auto& s : truth) grow(s.p);
  const double column = 0.5;
  const std::set<std::pair<int, int>> occupied_columns = occupiedColumns(log / "map.bt", column);
  for (const auto& [i, j] : occupied_columns) grow({(i + 0.5) * column, (j + 0.5) * column, 0});
  if (truth.empty()) {
    std::cerr << "auv mission report: " << (run / "ground_truth" / "trajectory.tum").string()
              << " has no poses\n";
    return 1;
  }
  lo -= Eigen::Vector2d::Constant(2.0);
  hi += Eigen::Vector2d::Constant(2.0);
  const double scale = std::clamp(900.0 / std::max(hi.x() - lo.x(), hi.y() - lo.y()), 4.0, 40.0);
  Figure figure(lo, hi, scale);
  for (const auto& [i, j] : occupied_columns) {
    figure.square({(i + 0.5) * column, (j + 0.5) * column, 0}, column, "#9a8c7a");
  }
  // Planner trees, then paths, then trajectories on top.
  drawTrees(figure, log);
  drawPaths(figure, log);
  std::vector<Eigen::Vector3d> true_line, estimate_line;
  for (const auto& s : truth) true_line.push_back(s.p);
  for (const auto& s : estimate) estimate_line.push_back(s.p);
  figure.polyline(estimate_line, "#ff8c00", 1.5);
  figure.polyline(true_line, "#1f4e9c", 2);
  for (const auto& w : mission.waypoints) figure.circle(w, 2.0, "#2e8b57", true);
  for (const auto& c : facts.collisions) figure.circle(c, 6.0, "#ff0000", false);
  for (const auto& r : mission.recovery_points) {
    figure.circle(r, 5.0, "#d2691e", false);
    figure.text(figure.x(r) + 6, figure.y(r) + 12, "R", "#d2691e");
  }
  for (const QueryRecord* q : mission.ordered) {
    figure.circle(q->start, 4.0, "#000000", true);
    figure.text(figure.x(q->start) + 5, figure.y(q->start) - 5, "q" + std::to_string(q->index + 1),
                "#000000");
  }
  drawLegend(figure, mission, facts, scale);

  std::error_code error;
  fs::create_directories(out_dir, error);
  if (!figure.write(out_dir / "report")) {
    std::cerr << "auv mission report: cannot write " << (out_dir / "report").string()
              << ".svg/.png\n";
    return 1;
  }
  const std::string summary = summaryJson(run, mission, facts, truth);
  std::ofstream(out_dir / "summary.json") << summary;
  std::cout << "figure: " << (out_dir / "report.svg").string() << " (and .png)"
            << "\nsummary: " << (out_dir / "summary.json").string() << "\n"
            << summary;
  return 0;
}

}  // namespace auv::mission
