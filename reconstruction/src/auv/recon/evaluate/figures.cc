#include "auv/recon/evaluate/figures.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <set>
#include <sstream>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/PointCloudIO.h>
#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/dense/fusion.h"
#include "auv/recon/evaluate/alignment.h"
#include "auv/recon/evaluate/ground_truth.h"
#include "auv/recon/evaluate/image_matching.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "figures";

const cv::Vec3b kNavigation(60, 200, 60);  // BGR green, as the paper's Figure 20
const cv::Vec3b kCameras(50, 50, 230);     // red
const cv::Vec3b kTruth(230, 230, 230);     // white

std::string cameraOfName(const std::string& name) {
  const size_t slash = name.find('/');
  return slash == std::string::npos ? std::string() : name.substr(0, slash);
}

std::string metres(double value) {
  std::ostringstream out;
  out << value << " m";
  return out.str();
}

/// Simulation times covered by the survey's recordings (frame sidecars); false when none.
bool recordedSpan(const Survey& survey, double& first, double& last) {
  first = std::numeric_limits<double>::infinity();
  last = -first;
  std::error_code error;
  if (!fs::is_directory(survey.recordings(), error)) return false;
  for (const auto& entry : fs::recursive_directory_iterator(survey.recordings(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 11 || name.substr(name.size() - 11) != ".frames.csv") continue;
    std::ifstream in(entry.path());
    std::string line;
    std::getline(in, line);  // header frame,camera_time_s,sim_time_s
    while (std::getline(in, line)) {
      const size_t comma = line.rfind(',');
      if (comma == std::string::npos || comma + 1 >= line.size()) continue;
      try {
        const double t = std::stod(line.substr(comma + 1));
        first = std::min(first, t);
        last = std::max(last, t);
      } catch (const std::exception&) {
        // an empty sim_time_s: a real camera's sidecar
      }
    }
  }
  return first <= last;
}

/// A rotation that takes the cloud's axis of least spread to z (top-down without truth).
Eigen::Matrix3d leastSpreadFrame(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= std::max<size_t>(1, points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Matrix3d R;  // rows: largest, middle, smallest spread
  R.row(0) = solver.eigenvectors().col(2).transpose();
  R.row(1) = solver.eigenvectors().col(1).transpose();
  R.row(2) = R.row(0).cross(R.row(1));
  return R;
}

void drawPolyline(cv::Mat& image, const TopDownView& view, const std::vector<Eigen::Vector2d>& xy,
                  const cv::Vec3b& color, int thickness) {
  std::vector<cv::Point> points;
  for (const auto& p : xy) points.push_back(view.pixel(p));
  if (points.size() >= 2) {
    cv::polylines(image, points, false, cv::Scalar(color[0], color[1], color[2]), thickness,
                  cv::LINE_AA);
  }
}

/// The true world seen from above: every triangle in the view, deepest first, lighter when
/// shallower (a relief map in place of the paper's satellite image).
void drawWorldRelief(cv::Mat& image, const TopDownView& view,
                     const open3d::geometry::TriangleMesh& mesh) {
  struct Face {
    double depth;
    std::array<cv::Point, 3> corners;
  };
  std::vector<Face> faces;
  const cv::Rect bounds(0, 0, image.cols, image.rows);
  for (const auto& t : mesh.triangles_) {
    Face face;
    bool inside = false;
    face.depth = 0;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d& v = mesh.vertices_[t(j)];
      face.corners[j] = view.pixel(v.head<2>());
      inside = inside || bounds.contains(face.corners[j]);
      face.depth += v.z() / 3.0;
    }
    if (inside) faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end(),
            [](const Face& a, const Face& b) { return a.depth > b.depth; });
  for (const Face& face : faces) {
    // 0 m (surface) -> 150, 10 m -> 40.
    const int grey = static_cast<int>(std::clamp(150.0 - 11.0 * face.depth, 40.0, 150.0));
    cv::fillConvexPoly(image, face.corners.data(), 3, cv::Scalar(grey, grey, grey), cv::LINE_AA);
  }
}

std::string svgColor(const cv::Vec3b& bgr) {
  std::ostringstream out;
  out << "rgb(" << int(bgr[2]) << "," << int(bgr[1]) << "," << int(bgr[0]) << ")";
  return out.str();
}

std::string svgPolyline(const TopDownView& view, const std::vector<Eigen::Vector2d>& xy,
                        const cv::Vec3b& color, double width) {
  std::ostringstream out;
  out << "<polyline fill=\"none\" stroke=\"" << svgColor(color) << "\" stroke-width=\"" << width
      << "\" points=\"";
  out << std::fixed << std::setprecision(1);
  for (const auto& p : xy) {
    const cv::Point2f q = view.pixel(p);
    out << q.x << "," << q.y << " ";
  }
  out << "\"/>\n";
  return out.str();
}

}  // namespace

void FiguresOptions::check() const {
  AUV_RECON_CHECK_OPTION(image_size_px >= 200 && image_size_px <= 16000, image_size_px,
                         "must be in [200, 16000] px");
  AUV_RECON_CHECK_OPTION(point_size_px >= 1 && point_size_px <= 20, point_size_px,
                         "must be in [1, 20] px");
  AUV_RECON_CHECK_OPTION(cloud == "auto" || cloud == "dense" || cloud == "sparse", cloud,
                         "must be auto, dense or sparse");
}

cv::Vec3b combinationColor(uint32_t mask, size_t camera_count) {
  if (camera_count <= 3) {
    // BGR channels per camera: first red, second green, third blue (the paper's legend style).
    const int channel[3] = {2, 1, 0};
    cv::Vec3b color(40, 40, 40);
    int count = 0;
    for (size_t i = 0; i < camera_count; ++i) {
      if (mask & (1u << i)) {
        color[channel[i]] = 255;
        ++count;
      }
    }
    if (count == 3) color = cv::Vec3b(255, 255, 255);
    return color;
  }
  // Distinct hues by the golden angle for larger rigs.
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar((mask * 137) % 180, 220, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr.at<cv::Vec3b>(0, 0);
}

std::string combinationName(uint32_t mask, const std::vector<std::string>& cameras) {
  std::string name;
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (mask & (1u << i)) name += (name.empty() ? "" : " + ") + cameras[i];
  }
  return name.empty() ? "none" : name;
}

TopDownView::TopDownView(const std::vector<Eigen::Vector2d>& points, int size_px, double margin) {
  min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  max_ = -min_;
  for (const auto& p : points) {
    min_ = min_.cwiseMin(p);
    max_ = max_.cwiseMax(p);
  }
  if (points.empty()) min_ = max_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d extent = (max_ - min_).cwiseMax(1e-3);
  min_ -= margin * extent;
  max_ += margin * extent;
  extent = max_ - min_;
  // Rows along north (x, decreasing downwards), columns along east (y).
  scale_ = size_px / std::max(extent.x(), extent.y());
  size_ = cv::Size(std::max(1, static_cast<int>(std::lround(extent.y() * scale_))),
                   std::max(1, static_cast<int>(std::lround(extent.x() * scale_))));
}

cv::Point2f TopDownView::pixel(const Eigen::Vector2d& xy) const {
  return cv::Point2f(static_cast<float>((xy.y() - min_.y()) * scale_),
                     static_cast<float>((max_.x() - xy.x()) * scale_));
}

cv::Mat drawTopDownCloud(const std::vector<Eigen::Vector3d>& points,
                         const std::vector<cv::Vec3b>& colors, const TopDownView& view,
                         int point_size_px) {
  cv::Mat image(view.size(), CV_8UC3, cv::Scalar(30, 30, 30));
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  // NED: larger z is deeper; draw the deepest first.
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return points[a].z() > points[b].z(); });
  const int half = point_size_px / 2;
  for (size_t i : order) {
    const cv::Point2f p = view.pixel(points[i].head<2>());
    const cv::Rect box(static_cast<int>(std::lround(p.x)) - half,
                       static_cast<int>(std::lround(p.y)) - half, point_size_px, point_size_px);
    image(box & cv::Rect(0, 0, image.cols, image.rows)).setTo(colors[i]);
  }
  return image;
}

void drawLegend(cv::Mat& image, const std::vector<std::pair<cv::Vec3b, std::string>>& entries,
                double pixels_per_metre) {
  const double font = std::max(0.4, image.cols / 2400.0);
  const int line = static_cast<int>(28 * font / 0.5);
  int width = 0;
  for (const auto& [color, label] : entries) {
    int baseline = 0;
    width =
        std::max(width, cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width);
  }
  const cv::Rect box(8, 8, width + line + 24, line * static_cast<int>(entries.size()) + 12);
  cv::Mat roi = image(box & cv::Rect(0, 0, image.cols, image.rows));
  roi = roi * 0.3;
  for (size_t i = 0; i < entries.size(); ++i) {
    const int y = 14 + line * static_cast<int>(i);
    const auto& c = entries[i].first;
    cv::rectangle(image, cv::Rect(16, y, line - 8, line - 8), cv::Scalar(c[0], c[1], c[2]),
                  cv::FILLED);
    cv::putText(image, entries[i].second, cv::Point(16 + line, y + line - 12),
                cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(240, 240, 240), 1, cv::LINE_AA);
  }
  // Scale bar: a round length near a fifth of the width.
  const double target = image.cols / 5.0 / pixels_per_metre;
  double length = std::pow(10.0, std::floor(std::log10(target)));
  for (double step : {2.0, 5.0}) {
    if (length * step <= target) length = std::pow(10.0, std::floor(std::log10(target))) * step;
  }
  const int bar = static_cast<int>(length * pixels_per_metre);
  const cv::Point start(16, image.rows - 20);
  cv::line(image, start, start + cv::Point(bar, 0), cv::Scalar(240, 240, 240), 3);
  cv::putText(image, metres(length), start + cv::Point(bar + 8, 6), cv::FONT_HERSHEY_SIMPLEX, font,
              cv::Scalar(240, 240, 240), 1, cv::LINE_AA);
}

FiguresResult writeFigures(const Survey& survey, const fs::path& ground_truth_run,
                           const FiguresOptions& options) {
  options.check();
  Survey::requireExists(survey.sparse() / "images.txt", kStage, "sfm");
  scene::Reconstruction sparse;
  try {
    sparse = scene::readColmapText(survey.sparse());
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("sparse model: ") + e.what());
  }
  // Cameras by name (the image names' folders), one bit each.
  std::vector<std::string> cameras;
  for (const auto& [id, image] : sparse.images) cameras.push_back(cameraOfName(image.name));
  std::sort(cameras.begin(), cameras.end());
  cameras.erase(std::unique(cameras.begin(), cameras.end()), cameras.end());
  if (cameras.size() > 31) throw StageError(kStage, "more than 31 cameras");
  std::map<uint32_t, uint32_t> bit_of_image;
  for (const auto& [id, image] : sparse.images) {
    const auto it = std::find(cameras.begin(), cameras.end(), cameraOfName(image.name));
    bit_of_image[id] = 1u << static_cast<uint32_t>(it - cameras.begin());
  }
  auto maskOf = [&](const auto& image_ids) {
    uint32_t mask = 0;
    for (uint32_t id : image_ids) {
      const auto it = bit_of_image.find(id);
      if (it != bit_of_image.end()) mask |= it->second;
    }
    return mask;
  };

  // The cloud and each point's cameras.
  FiguresResult result;
  std::vector<Eigen::Vector3d> points;
  std::vector<uint32_t> masks;
  const fs::path fused = survey.dense() / "fused.ply", views = survey.dense() / "fused_views.bin";
  if (options.cloud != "sparse" && fs::exists(fused) && fs::exists(views)) {
    open3d::geometry::PointCloud cloud;
    if (!open3d::io::ReadPointCloud(fused.string(), cloud)) {
      throw StageError(kStage, fused.string() + ": unreadable point cloud");
    }
    std::vector<std::vector<uint32_t>> images;
    try {
      images = dense::readFusedViews(views);
    } catch (const std::exception& e) {
      throw StageError(kStage, e.what());
    }
    if (images.size() != cloud.points_.size()) {
      throw StageError(kStage, views.string() + ": " + std::to_string(images.size()) + " points, " +
                                   fused.string() + " has " + std::to_string(cloud.points_.size()));
    }
    points = cloud.points_;
    for (const auto& list : images) masks.push_back(maskOf(list));
    result.cloud = "dense";
  } else if (options.cloud == "dense") {
    throw StageError(kStage, "no dense cloud with views (" + fused.string() + " and " +
                                 views.string() + "; run `auv recon dense`)");
  } else {
    for (const auto& [id, point] : sparse.points) {
      std::vector<uint32_t> ids;
      for (const auto& e : point.track) ids.push_back(e.image_id);
      points.push_back(point.xyz);
      masks.push_back(maskOf(ids));
    }
    result.cloud = "sparse";
  }
  // Points no image produced (empty tracks) have no colour to show.
  {
    size_t kept = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (masks[i] == 0) continue;
      points[kept] = points[i];
      masks[kept++] = masks[i];
    }
    points.resize(kept);
    masks.resize(kept);
  }
  if (points.empty()) {
    throw StageError(kStage, "the " + result.cloud + " cloud has no point with its cameras");
  }

  // Into the truth's frame when there is one (north up, depth z), else down the least spread.
  std::unique_ptr<GroundTruth> truth;
  Similarity to_world;
  if (!ground_truth_run.empty()) {
    truth = std::make_unique<GroundTruth>(GroundTruth::load(ground_truth_run));
    std::map<std::string, std::vector<KeyframeSource>> sources;
    if (fs::is_directory(survey.keyframes())) sources = readKeyframeSources(survey.keyframes());
    const ImageMatching matching = matchImages(sparse, sources, *truth);
    const AlignmentResult alignment = alignToTruth(posePairs(matching, sparse), AlignmentOptions{});
    if (alignment.status != AlignmentStatus::SUCCESS) {
      throw StageError(kStage, "alignment to the ground truth failed: " + alignment.message);
    }
    to_world = alignment.similarity;
  } else {
    to_world.rotation = leastSpreadFrame(points);
  }
  for (auto& p : points) p = to_world.apply(p);

  StagedOutput output(survey.root() / "figures");
  // (a) per-camera contribution.
  std::vector<cv::Vec3b> colors;
  std::map<uint32_t, size_t> count_of;
  for (uint32_t mask : masks) {
    colors.push_back(combinationColor(mask, cameras.size()));
    ++count_of[mask];
  }
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : points) xy.push_back(p.head<2>());
  const TopDownView view(xy, options.image_size_px);
  cv::Mat image = drawTopDownCloud(points, colors, view, options.point_size_px);
  std::vector<std::pair<cv::Vec3b, std::string>> legend;
  for (const auto& [mask, count] : count_of) {
    std::ostringstream label;
    label << combinationName(mask, cameras) << "  " << std::fixed << std::setprecision(1)
          << 100.0 * count / points.size() << " %";
    legend.push_back({combinationColor(mask, cameras.size()), label.str()});
    result.points_per_combination[combinationName(mask, cameras)] = count;
  }
  drawLegend(image, legend, view.pixelsPerMetre());
  if (!cv::imwrite((output.path() / "cameras.png").string(), image)) {
    throw StageError(kStage, (output.path() / "cameras.png").string() + ": cannot write");
  }
  scene::PlyData ply;
  ply.positions = points;
  for (const auto& c : colors) ply.colors.emplace_back(c[2], c[1], c[0]);
  scene::writePly(output.path() / "cameras.ply", ply);
  result.files = {output.finalPath() / "cameras.png", output.finalPath() / "cameras.ply"};
  result.points = points.size();

  // (b) trajectories: navigation vs SfM cameras, over the truth.
  if (truth) {
    std::vector<StampedPose> navigation = truth->navigationTrajectory();
    std::vector<StampedPose> true_path = truth->trueTrajectory();
    double first = 0, last = 0;
    if (recordedSpan(survey, first, last)) {
      auto clip = [&](std::vector<StampedPose>& poses) {
        poses.erase(std::remove_if(poses.begin(), poses.end(),
                                   [&](const StampedPose& p) {
                                     return p.time < first - 5 || p.time > last + 5;
                                   }),
                    poses.end());
      };
      clip(navigation);
      clip(true_path);
    }
    std::map<std::string, std::vector<std::pair<std::string, Eigen::Vector2d>>> per_camera;
    std::vector<Eigen::Vector2d> everything;
    for (const auto& [id, im] : sparse.images) {
      const Eigen::Vector3d c = to_world.apply(im.center());
      per_camera[cameraOfName(im.name)].push_back({im.name, c.head<2>()});
      everything.push_back(c.head<2>());
    }
    std::vector<Eigen::Vector2d> nav_xy, true_xy;
    for (const auto& p : navigation) nav_xy.push_back(p.position.head<2>());
    for (const auto& p : true_path) true_xy.push_back(p.position.head<2>());
    everything.insert(everything.end(), nav_xy.begin(), nav_xy.end());
    everything.insert(everything.end(), true_xy.begin(), true_xy.end());
    const TopDownView tview(everything, options.image_size_px, 0.15);
    cv::Mat figure(tview.size(), CV_8UC3, cv::Scalar(25, 25, 25));
    drawWorldRelief(figure, tview, *truth->worldMesh());
    drawPolyline(figure, tview, true_xy, kTruth, 1);
    drawPolyline(figure, tview, nav_xy, kNavigation, 2);
    std::ostringstream svg;
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << tview.size().width
        << "\" height=\"" << tview.size().height << "\">\n<rect width=\"100%\" height=\"100%\" "
        << "fill=\"rgb(25,25,25)\"/>\n"
        << svgPolyline(tview, true_xy, kTruth, 1) << svgPolyline(tview, nav_xy, kNavigation, 2);
    for (auto& [camera, list] : per_camera) {
      std::sort(list.begin(), list.end(),
                [](const auto& a, const auto& b) { return a.first < b.first; });
      std::vector<Eigen::Vector2d> centres;
      for (const auto& [name, c] : list) centres.push_back(c);
      drawPolyline(figure, tview, centres, kCameras, 1);
      for (const auto& c : centres) {
        cv::circle(figure, tview.pixel(c), 3, cv::Scalar(kCameras[0], kCameras[1], kCameras[2]),
                   cv::FILLED, cv::LINE_AA);
      }
      svg << svgPolyline(tview, centres, kCameras, 1.5);
    }
    drawLegend(figure,
               {{kNavigation, "vehicle navigation (dead reckoning)"},
                {kCameras, "SfM cameras (aligned to the truth)"},
                {kTruth, "true trajectory"}},
               tview.pixelsPerMetre());
    svg << "<text x=\"16\" y=\"24\" fill=\"" << svgColor(kNavigation)
        << "\" font-family=\"sans-serif\">vehicle navigation</text>\n"
        << "<text x=\"16\" y=\"44\" fill=\"" << svgColor(kCameras)
        << "\" font-family=\"sans-serif\">SfM cameras (aligned)</text>\n"
        << "<text x=\"16\" y=\"64\" fill=\"" << svgColor(kTruth)
        << "\" font-family=\"sans-serif\">true trajectory</text>\n</svg>\n";
    if (!cv::imwrite((output.path() / "trajectory.png").string(), figure)) {
      throw StageError(kStage, (output.path() / "trajectory.png").string() + ": cannot write");
    }
    writeFileAtomically(output.path() / "trajectory.svg", svg.str());
    result.files.push_back(output.finalPath() / "trajectory.png");
    result.files.push_back(output.finalPath() / "trajectory.svg");
    result.trajectory = true;
  }
  output.commit();

  nlohmann::json section = {{"cloud", result.cloud},
                            {"points", result.points},
                            {"trajectory", result.trajectory},
                            {"aligned_to_truth", truth != nullptr}};
  for (const auto& [name, count] : result.points_per_combination) {
    section["fraction_per_cameras"][name] = static_cast<double>(count) / result.points;
  }
  updateReport(survey.report(), kStage, section);
  return result;
}

}  // namespace auv::recon::evaluate
