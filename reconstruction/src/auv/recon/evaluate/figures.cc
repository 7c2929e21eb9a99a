#include "auv/recon/evaluate/figures.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
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
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;

namespace auv::recon::evaluate {
namespace {

constexpr const char* kStage = "figures";

const cv::Vec3b kNavigation(60, 200, 60);  // BGR green, as the paper's Figure 20
const cv::Vec3b kCameras(50, 50, 230);     // red
const cv::Vec3b kTruth(230, 230, 230);     // white

// Figure 20's framing: a long straight traverse would otherwise be a strip of its own width.
constexpr double kTrajectoryReliefM = 4.0;    // m of relief at least around the paths
constexpr double kTrajectoryMinAspect = 0.5;  // shorter side / longer side at least

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kCorner = 8;  // px, from the image's edges to the legend and scale bar
const char* const kWidestScale = "0.0005 m";  // no scale-bar label is wider
const cv::Scalar kLegendText(240, 240, 240);

std::string cameraOfName(const std::string& name) {
  const size_t slash = name.find('/');
  return slash == std::string::npos ? std::string() : name.substr(0, slash);
}

std::string metres(double value) {
  std::ostringstream out;
  out << value << " m";
  return out.str();
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

/// Where the legend and the scale bar go: one layout for the PNG and the SVG.
struct LegendLayout {
  int line = 0;                    // px, height of a row
  cv::Rect box;                    // the darkened box behind the rows
  std::vector<cv::Rect> swatches;  // colour squares
  std::vector<cv::Point> origins;  // text origins (left end of the baseline)
  std::vector<int> widths;         // px, measured width of each label
  cv::Size scale_text;             // px, the widest scale-bar label
  int scale_baseline = 0;          // px, below the scale-bar label's baseline
};

LegendLayout layoutLegend(const std::vector<LegendEntry>& entries, double font) {
  LegendLayout layout;
  layout.line = static_cast<int>(std::lround(56 * font));
  int width = 0, baseline = 0;
  for (const auto& entry : entries) {
    layout.widths.push_back(cv::getTextSize(entry.second, kFont, font, 1, &baseline).width);
    width = std::max(width, layout.widths.back());
  }
  const int rows = static_cast<int>(entries.size());
  layout.box = cv::Rect(kCorner, kCorner, width + layout.line + 24, layout.line * rows + 12);
  for (int i = 0; i < rows; ++i) {
    const int y = kCorner + 6 + layout.line * i;
    layout.swatches.emplace_back(16, y, layout.line - 8, layout.line - 8);
    layout.origins.emplace_back(16 + layout.line, y + layout.line - 12);
  }
  layout.scale_text = cv::getTextSize(kWidestScale, kFont, font, 1, &layout.scale_baseline);
  return layout;
}

/// A round length near a fifth of the image's width, bottom-left, below the legend.
struct ScaleBar {
  cv::Point start;  // left end
  int length_px = 0;
  cv::Point label_origin;
  std::string label;
};

ScaleBar scaleBar(const cv::Size& image, double pixels_per_metre, const LegendLayout& layout) {
  const double target = image.width / 5.0 / pixels_per_metre;
  const double decade = std::pow(10.0, std::floor(std::log10(target)));
  double length = decade;
  for (double step : {2.0, 5.0}) {
    if (decade * step <= target) length = decade * step;
  }
  ScaleBar bar;
  bar.length_px = static_cast<int>(length * pixels_per_metre);
  bar.label = metres(length);
  const int baseline_y = image.height - kCorner - layout.scale_baseline;
  bar.start = cv::Point(16, baseline_y - layout.scale_text.height / 2);
  bar.label_origin = cv::Point(16 + bar.length_px + 8, baseline_y);
  return bar;
}

std::string svgLegend(const std::vector<LegendEntry>& entries, double font, const cv::Size& image,
                      double pixels_per_metre) {
  const LegendLayout layout = layoutLegend(entries, font);
  const ScaleBar bar = scaleBar(image, pixels_per_metre, layout);
  // textLength: the viewer's font may be wider than OpenCV's; the text is squeezed, never cut.
  auto text = [&](const cv::Point& origin, int width, const std::string& label) {
    std::ostringstream out;
    out << "<text x=\"" << origin.x << "\" y=\"" << origin.y << "\" font-size=\""
        << std::lround(30 * font) << "\" textLength=\"" << width
        << "\" lengthAdjust=\"spacingAndGlyphs\" fill=\"rgb(240,240,240)\" "
           "font-family=\"sans-serif\">"
        << label << "</text>\n";
    return out.str();
  };
  std::ostringstream out;
  out << "<rect x=\"" << layout.box.x << "\" y=\"" << layout.box.y << "\" width=\""
      << layout.box.width << "\" height=\"" << layout.box.height
      << "\" fill=\"black\" fill-opacity=\"0.7\"/>\n";
  for (size_t i = 0; i < entries.size(); ++i) {
    const cv::Rect& s = layout.swatches[i];
    out << "<rect x=\"" << s.x << "\" y=\"" << s.y << "\" width=\"" << s.width << "\" height=\""
        << s.height << "\" fill=\"" << svgColor(entries[i].first) << "\"/>\n"
        << text(layout.origins[i], layout.widths[i], entries[i].second);
  }
  int baseline = 0;
  out << "<line x1=\"" << bar.start.x << "\" y1=\"" << bar.start.y << "\" x2=\""
      << bar.start.x + bar.length_px << "\" y2=\"" << bar.start.y
      << "\" stroke=\"rgb(240,240,240)\" stroke-width=\"3\"/>\n"
      << text(bar.label_origin, cv::getTextSize(bar.label, kFont, font, 1, &baseline).width,
              bar.label);
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

TopDownView::TopDownView(const std::vector<Eigen::Vector2d>& points, int size_px,
                         const TopDownFraming& framing) {
  if (!(framing.margin >= 0 && framing.min_margin_m >= 0 && framing.min_aspect >= 0 &&
        framing.min_aspect <= 1)) {
    throw std::invalid_argument("TopDownView: margin " + std::to_string(framing.margin) +
                                ", min_margin_m " + std::to_string(framing.min_margin_m) +
                                ", min_aspect " + std::to_string(framing.min_aspect) +
                                ": margins must be >= 0, min_aspect in [0, 1]");
  }
  min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  max_ = -min_;
  for (const auto& p : points) {
    min_ = min_.cwiseMin(p);
    max_ = max_.cwiseMax(p);
  }
  if (points.empty()) min_ = max_ = Eigen::Vector2d::Zero();
  const Eigen::Vector2d pad =
      (framing.margin * (max_ - min_).cwiseMax(1e-3)).cwiseMax(framing.min_margin_m);
  min_ -= pad;
  max_ += pad;
  // Widens axis (0 north, 1 east) to at least `length` m about its centre.
  auto widen = [&](int axis, double length) {
    const double centre = 0.5 * (min_[axis] + max_[axis]);
    const double half = 0.5 * std::max(length, max_[axis] - min_[axis]);
    min_[axis] = centre - half;
    max_[axis] = centre + half;
  };
  widen(0, framing.min_aspect * (max_.y() - min_.y()));
  widen(1, framing.min_aspect * (max_.x() - min_.x()));
  // Rows along north (x, decreasing downwards), columns along east (y).
  scale_ = size_px / (max_ - min_).maxCoeff();
  widen(0, framing.min_size_px.height / scale_);
  widen(1, framing.min_size_px.width / scale_);
  const Eigen::Vector2d extent = max_ - min_;
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

double legendFontScale(int size_px) { return std::max(0.4, size_px / 2400.0); }

cv::Size legendImageSize(const std::vector<LegendEntry>& entries, double font_scale) {
  const LegendLayout layout = layoutLegend(entries, font_scale);
  // The scale bar is at most a fifth of the width; its label follows it.
  const int bar_width = (5 * (16 + 8 + layout.scale_text.width + kCorner) + 3) / 4;
  return cv::Size(
      std::max(layout.box.br().x + kCorner, bar_width),
      layout.box.br().y + 2 * kCorner + layout.scale_text.height + layout.scale_baseline + kCorner);
}

cv::Rect drawLegend(cv::Mat& image, const std::vector<LegendEntry>& entries,
                    double pixels_per_metre, double font_scale) {
  const cv::Size need = legendImageSize(entries, font_scale);
  if (image.cols < need.width || image.rows < need.height) {
    throw std::invalid_argument("drawLegend: a " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " image cannot hold the legend (" +
                                std::to_string(need.width) + "x" + std::to_string(need.height) +
                                " px)");
  }
  const LegendLayout layout = layoutLegend(entries, font_scale);
  cv::Mat roi = image(layout.box);
  roi = roi * 0.3;
  for (size_t i = 0; i < entries.size(); ++i) {
    const auto& c = entries[i].first;
    cv::rectangle(image, layout.swatches[i], cv::Scalar(c[0], c[1], c[2]), cv::FILLED);
    cv::putText(image, entries[i].second, layout.origins[i], kFont, font_scale, kLegendText, 1,
                cv::LINE_AA);
  }
  const ScaleBar bar = scaleBar(image.size(), pixels_per_metre, layout);
  cv::line(image, bar.start, bar.start + cv::Point(bar.length_px, 0), kLegendText, 3);
  cv::putText(image, bar.label, bar.label_origin, kFont, font_scale, kLegendText, 1, cv::LINE_AA);
  return layout.box;
}

FiguresStageResult writeFigures(const Survey& survey, const fs::path& ground_truth_run,
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
  FiguresStageResult result;
  std::vector<Eigen::Vector3d> points;
  std::vector<uint32_t> masks;
  const fs::path fused = survey.dense() / "fused.ply", views = survey.dense() / "fused_views.bin";
  if (options.cloud != "sparse" && fs::exists(fused) && fs::exists(views)) {
    open3d::geometry::PointCloud cloud;
    if (!scene::readPointCloud(fused, cloud)) {
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
  std::vector<LegendEntry> legend;
  for (const auto& [mask, count] : count_of) {
    std::ostringstream label;
    label << combinationName(mask, cameras) << "  " << std::fixed << std::setprecision(1)
          << 100.0 * count / points.size() << " %";
    legend.push_back({combinationColor(mask, cameras.size()), label.str()});
    result.points_per_combination[combinationName(mask, cameras)] = count;
  }
  const double font = legendFontScale(options.image_size_px);
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : points) xy.push_back(p.head<2>());
  TopDownFraming framing;
  framing.min_size_px = legendImageSize(legend, font);
  const TopDownView view(xy, options.image_size_px, framing);
  cv::Mat image = drawTopDownCloud(points, colors, view, options.point_size_px);
  drawLegend(image, legend, view.pixelsPerMetre(), font);
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
    if (recordedSimSpan(survey, first, last)) {
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
    const std::vector<LegendEntry> trajectory_legend = {
        {kNavigation, "vehicle navigation (dead reckoning)"},
        {kCameras, "SfM cameras (aligned to the truth)"},
        {kTruth, "true trajectory"}};
    TopDownFraming tframing;
    tframing.margin = 0.15;
    tframing.min_margin_m = kTrajectoryReliefM;
    tframing.min_aspect = kTrajectoryMinAspect;
    tframing.min_size_px = legendImageSize(trajectory_legend, font);
    const TopDownView tview(everything, options.image_size_px, tframing);
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
    drawLegend(figure, trajectory_legend, tview.pixelsPerMetre(), font);
    svg << svgLegend(trajectory_legend, font, tview.size(), tview.pixelsPerMetre()) << "</svg>\n";
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
