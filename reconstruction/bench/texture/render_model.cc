// Looks at a survey's textured model (issue 7): renders `textured/model.obj` at the registered
// cameras' poses of `sparse/` (renderTexturedModel, no GL) and writes each rendering beside the
// corrected photo (photo | render), with the PSNR over the pixels the model covers and the
// covered fraction of the image. With --yaw-deg the same cameras are also turned about the
// model's centre (novel views, no photo to compare with: coverage only).
//
// The PSNR is split by where the texture of a pixel's face comes from (textured/face_views.csv):
// pixels textured from this very photo ("own") measure the registration of mesh, poses and
// atlas; the others also carry the lighting and exposure differences between the photos.
//
//   render_model --survey S --out DIR [--views N] [--yaw-deg D] [--back M] [--scale F]
//
// --views N   N registered images, evenly spread over the names (default all)
// --yaw-deg D also render each chosen camera turned by D degrees about the vertical through the
//             model's centre (the vertical: the mean of the cameras' up directions)
// --back M    for the turned views, step back M model units along the optical axis
// --scale F   render and compare at F times the photos' resolution (default 0.5)
//
// Writes DIR/<image stem>.png (photo | render), DIR/<image stem>_yaw<D>.png (photo of the
// original pose | novel view) and DIR/render_model.md (the table it also prints).
// Exit 1 when the survey lacks sparse/ or textured/model.obj or a photo, 2 for bad flags.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/texture/rasterizer.h"
#include "auv/recon/texture/textured_model.h"

namespace fs = std::filesystem;
using auv::recon::StageError;
using auv::recon::Survey;
using namespace auv::recon::texture;

namespace {

constexpr const char* kUsage =
    "usage: render_model --survey S --out DIR [--views N] [--yaw-deg D] [--back M] [--scale F]\n";

struct Args {
  fs::path survey, out;
  int views = 0;  // 0: all
  double yaw_deg = 0, back = 0, scale = 0.5;
  bool yaw = false;
};

double number(const std::string& flag, const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value)) {
    throw std::invalid_argument(flag + ": not a number: '" + text + "'");
  }
  return value;
}

Args parse(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::cout << kUsage;
      std::exit(0);
    }
    if (i + 1 >= argc) throw std::invalid_argument(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--survey") {
      args.survey = value;
    } else if (flag == "--out") {
      args.out = value;
    } else if (flag == "--views") {
      const double n = number(flag, value);
      if (n < 1 || n != std::floor(n)) {
        throw std::invalid_argument("--views: must be an integer >= 1, got " + value);
      }
      args.views = static_cast<int>(n);
    } else if (flag == "--yaw-deg") {
      args.yaw_deg = number(flag, value);
      args.yaw = true;
    } else if (flag == "--back") {
      args.back = number(flag, value);
    } else if (flag == "--scale") {
      args.scale = number(flag, value);
      if (args.scale <= 0 || args.scale > 1) {
        throw std::invalid_argument("--scale: must be in (0, 1], got " + value);
      }
    } else {
      throw std::invalid_argument("unknown flag " + flag);
    }
  }
  if (args.survey.empty()) throw std::invalid_argument("--survey is required");
  if (args.out.empty()) throw std::invalid_argument("--out is required");
  return args;
}

double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The view at `scale` times the resolution: pixel centres at integers, so the principal point
/// maps like cv::resize's pixel grid, (c + 0.5) * s - 0.5.
ViewGeometry scaled(ViewGeometry view, cv::Size size) {
  const double sx = static_cast<double>(size.width) / view.camera.width;
  const double sy = static_cast<double>(size.height) / view.camera.height;
  view.camera.width = size.width;
  view.camera.height = size.height;
  view.camera.fx *= sx;
  view.camera.fy *= sy;
  view.camera.cx = (view.camera.cx + 0.5) * sx - 0.5;
  view.camera.cy = (view.camera.cy + 0.5) * sy - 0.5;
  return view;
}

/// Median of each coordinate: the model's centre, robust to stray far faces.
Eigen::Vector3d medianCentre(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d centre;
  std::vector<double> values(points.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (size_t i = 0; i < points.size(); ++i) values[i] = points[i][axis];
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    centre[axis] = values[values.size() / 2];
  }
  return centre;
}

/// `view` turned by `angle` (rad) about the axis `up` through `centre`, then moved `back` along
/// its optical axis: camera->world' = turn * camera->world.
ViewGeometry turned(ViewGeometry view, const Eigen::Vector3d& centre, const Eigen::Vector3d& up,
                    double angle, double back) {
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(angle, up).toRotationMatrix();
  turn.translation() = centre - turn.linear() * centre;
  view.world_to_camera = view.world_to_camera * turn.inverse();
  view.world_to_camera.translation().z() += back;  // camera z of everything grows by `back`
  return view;
}

std::string stemOf(const std::string& name) {
  std::string stem = fs::path(name).replace_extension().string();
  std::replace(stem.begin(), stem.end(), '/', '_');
  return stem;
}

std::string fixed(double value, int digits) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(digits) << value;
  return text.str();
}

/// Per face, the index in `names` of the image that textures it (-1: unseen or unknown), from
/// textured/face_views.csv (`face,image`); empty when the file is missing.
std::vector<int> readFaceViews(const fs::path& file, size_t faces,
                               std::vector<std::string>& names) {
  std::vector<int> labels;
  std::ifstream in(file);
  if (!in) return labels;
  labels.assign(faces, -1);
  std::string line;
  std::getline(in, line);  // header
  for (int number = 2; std::getline(in, line); ++number) {
    const size_t comma = line.find(',');
    size_t face = 0;
    try {
      face = std::stoul(line.substr(0, comma));
    } catch (const std::exception&) {
      face = faces;
    }
    if (comma == std::string::npos || face >= faces) {
      throw StageError("render_model", file.string() + ":" + std::to_string(number) +
                                           ": expected `face,image` with a face below " +
                                           std::to_string(faces));
    }
    const std::string name = line.substr(comma + 1);
    if (name.empty()) continue;
    auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end()) found = names.insert(names.end(), name);
    labels[face] = static_cast<int>(found - names.begin());
  }
  return labels;
}

/// PSNR over `mask` and its pixel count ("—" when empty).
std::string maskedPsnr(const cv::Mat3b& image, const cv::Mat3b& reference, const cv::Mat1b& mask,
                       size_t& pixels) {
  pixels = static_cast<size_t>(cv::countNonZero(mask));
  return pixels == 0 ? "—" : fixed(psnr(image, reference, mask), 2);
}

void writePng(const fs::path& file, const cv::Mat& image) {
  if (!cv::imwrite(file.string(), image)) {
    throw std::runtime_error(file.string() + ": cannot write the image");
  }
}

int run(const Args& args) {
  const Survey survey(args.survey);
  Survey::requireExists(survey.sparse() / "images.txt", "render_model", "sfm");
  const fs::path obj = survey.textured() / "model.obj";
  Survey::requireExists(obj, "render_model", "texture");

  auto start = std::chrono::steady_clock::now();
  const auv::recon::scene::Reconstruction sparse =
      auv::recon::scene::readColmapText(survey.sparse());
  if (sparse.images.empty()) {
    throw StageError("render_model",
                     (survey.sparse() / "images.txt").string() + ": no registered images");
  }
  const TexturedModel model = readObj(obj);
  if (model.faces.empty()) throw StageError("render_model", obj.string() + ": no faces");
  std::vector<std::string> label_names;
  const fs::path face_views_file = survey.textured() / "face_views.csv";
  const std::vector<int> face_views =
      readFaceViews(face_views_file, model.faces.size(), label_names);
  const double read_s = seconds(start);
  std::cout << "read " << obj.string() << ": " << model.vertices.size() << " vertices, "
            << model.faces.size() << " faces, " << model.pages.size() << " pages ("
            << fixed(read_s, 1) << " s); " << sparse.images.size() << " registered images\n";

  // Images sorted by name, N of them evenly spread.
  std::vector<const auv::recon::scene::Image*> images;
  for (const auto& [id, image] : sparse.images) images.push_back(&image);
  std::sort(images.begin(), images.end(), [](auto* a, auto* b) { return a->name < b->name; });
  if (args.views > 0 && args.views < static_cast<int>(images.size())) {
    std::vector<const auv::recon::scene::Image*> chosen;
    for (int k = 0; k < args.views; ++k) {
      chosen.push_back(images[k * images.size() / args.views]);
    }
    images = chosen;
  }

  // Vertical for the turned views: the cameras' mean up (camera -y) direction.
  const Eigen::Vector3d centre = medianCentre(model.vertices);
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& [id, image] : sparse.images) {
    up += image.rotation().transpose() * Eigen::Vector3d(0, -1, 0);
  }
  up.normalize();

  fs::create_directories(args.out);
  std::ostringstream table;
  table << "| view | pose | PSNR dB (covered) | coverage | PSNR dB own px (fraction) | PSNR dB "
           "other px | render s | file |\n"
        << "|---|---|---|---|---|---|---|---|\n";
  double sum_mse = 0;
  size_t sum_pixels = 0;
  for (const auto* image : images) {
    const auv::recon::scene::Camera& camera = sparse.cameraOf(*image);
    const fs::path photo_file = survey.corrected() / image->name;
    const cv::Mat3b photo = cv::imread(photo_file.string(), cv::IMREAD_COLOR);
    if (photo.empty()) {
      throw StageError("render_model", photo_file.string() + ": cannot read the photo of " +
                                           image->name + " (missing corrected/ image?)");
    }
    if (photo.cols != camera.width || photo.rows != camera.height) {
      throw StageError("render_model",
                       photo_file.string() + ": image is " + std::to_string(photo.cols) + "x" +
                           std::to_string(photo.rows) + ", its camera " +
                           std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
    const cv::Size size(std::max(1, static_cast<int>(std::lround(camera.width * args.scale))),
                        std::max(1, static_cast<int>(std::lround(camera.height * args.scale))));
    cv::Mat3b reference;
    cv::resize(photo, reference, size, 0, 0, cv::INTER_AREA);
    ViewGeometry view;
    view.camera = camera;
    view.world_to_camera = image->worldToCamera();
    view = scaled(view, size);

    struct Pose {
      std::string label, suffix;
      ViewGeometry view;
      bool compare;
    };
    std::vector<Pose> poses = {{"registered", "", view, true}};
    if (args.yaw) {
      poses.push_back({"turned " + fixed(args.yaw_deg, 0) + " deg" +
                           (args.back != 0 ? ", back " + fixed(args.back, 1) : ""),
                       "_yaw" + fixed(args.yaw_deg, 0),
                       turned(view, centre, up, args.yaw_deg * M_PI / 180, args.back), false});
    }
    for (const Pose& pose : poses) {
      start = std::chrono::steady_clock::now();
      const Rendering rendering = renderTexturedModel(model, pose.view);
      const double render_s = seconds(start);
      const size_t covered = static_cast<size_t>(cv::countNonZero(rendering.mask));
      const double coverage = static_cast<double>(covered) / rendering.mask.total();
      std::string psnr_text = "—", own_text = "—", other_text = "—";
      if (pose.compare && covered > 0) {
        const double db = psnr(rendering.image, reference, rendering.mask);
        psnr_text = fixed(db, 2);
        sum_mse += 255.0 * 255.0 * std::pow(10.0, -db / 10) * covered;
        sum_pixels += covered;
        if (!face_views.empty()) {
          // Which faces the renderer drew: the same z-buffer, face indices this time.
          const RasterBuffers raster = rasterize(model.vertices, model.faces, pose.view);
          const auto self = std::find(label_names.begin(), label_names.end(), image->name);
          const int own_label =
              self == label_names.end() ? -2 : static_cast<int>(self - label_names.begin());
          cv::Mat1b own(rendering.mask.size(), uchar(0)), other(rendering.mask.size(), uchar(0));
          for (int y = 0; y < own.rows; ++y) {
            for (int x = 0; x < own.cols; ++x) {
              const int face = raster.face(y, x);
              if (face < 0 || !rendering.mask(y, x)) continue;
              (face_views[face] == own_label ? own : other)(y, x) = 255;
            }
          }
          size_t own_pixels = 0, other_pixels = 0;
          own_text = maskedPsnr(rendering.image, reference, own, own_pixels);
          own_text += " (" + fixed(static_cast<double>(own_pixels) / covered, 2) + ")";
          other_text = maskedPsnr(rendering.image, reference, other, other_pixels);
        }
      }
      cv::Mat side;
      cv::hconcat(reference, rendering.image, side);
      const fs::path file = args.out / (stemOf(image->name) + pose.suffix + ".png");
      writePng(file, side);
      table << "| " << image->name << " | " << pose.label << " | " << psnr_text << " | "
            << fixed(coverage, 3) << " | " << own_text << " | " << other_text << " | "
            << fixed(render_s, 2) << " | " << file.filename().string() << " |\n";
      std::cout << image->name << " (" << pose.label << "): PSNR " << psnr_text << " dB over "
                << covered << " covered px (own-view px " << own_text << ", other px " << other_text
                << "), coverage " << fixed(coverage, 3) << ", " << fixed(render_s, 2) << " s -> "
                << file.string() << std::endl;
    }
  }
  std::ostringstream md;
  md << "Textured model `" << obj.string() << "`: " << model.faces.size() << " faces, "
     << model.pages.size() << " atlas page(s); " << images.size() << " of " << sparse.images.size()
     << " registered views rendered at " << args.scale
     << " x the photos' resolution (photo downsampled with INTER_AREA), read in "
     << fixed(read_s, 1) << " s. Own px: pixels whose face is textured from this photo ("
     << (face_views.empty() ? face_views_file.string() + " missing: not split"
                            : "textured/face_views.csv")
     << "); other px: from another photo.\n\n"
     << table.str() << '\n';
  if (sum_pixels > 0) {
    const double mse = sum_mse / sum_pixels;
    md << "All registered views together: PSNR " << fixed(10 * std::log10(255.0 * 255.0 / mse), 2)
       << " dB over " << sum_pixels << " covered pixels.\n";
  }
  std::ofstream(args.out / "render_model.md") << md.str();
  std::cout << '\n' << md.str() << "written " << (args.out / "render_model.md").string() << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "render_model: error: " << e.what() << '\n' << kUsage;
    return 2;
  }
  try {
    return run(args);
  } catch (const StageError& e) {  // what() starts with the stage name: print the cause once
    std::cerr << "render_model: error: " << std::string(e.what()).substr(e.stage().size() + 2)
              << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "render_model: error: " << e.what() << '\n';
    return 1;
  }
}
