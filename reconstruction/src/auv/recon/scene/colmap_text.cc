#include "auv/recon/scene/colmap_text.h"

#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon::scene {

namespace {

constexpr double kColmapPixelOffset = 0.5;

/// Lines of a COLMAP text file without comments, with their numbers, for error messages.
class LineReader {
 public:
  explicit LineReader(const fs::path& file) : file_(file), in_(file) {
    if (!in_) throw std::runtime_error(file.string() + ": cannot open");
  }
  /// The next line that is not a comment; false at the end. `keep_empty` returns empty lines
  /// too (the keypoint line of an image may be empty).
  bool next(std::string& line, bool keep_empty = false) {
    while (std::getline(in_, line)) {
      ++number_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!line.empty() && line[0] == '#') continue;
      if (line.find_first_not_of(" \t") == std::string::npos) {
        if (keep_empty) {
          line.clear();
          return true;
        }
        continue;
      }
      return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(file_.string() + ":" + std::to_string(number_) + ": " + why);
  }

 private:
  fs::path file_;
  std::ifstream in_;
  int number_ = 0;
};

template <class T>
T field(std::istringstream& in, LineReader& reader, const char* name) {
  T value{};
  if (!(in >> value)) reader.fail(std::string("missing or malformed ") + name);
  return value;
}

size_t parameterCount(CameraModel model) {
  switch (model) {
    case CameraModel::SIMPLE_PINHOLE:
      return 3;
    case CameraModel::PINHOLE:
      return 4;
    case CameraModel::OPENCV:
      return 8;
    case CameraModel::FULL_OPENCV:
      return 12;
  }
  return 0;
}

std::ofstream openForWriting(const fs::path& temp) {
  std::ofstream out(temp);
  if (!out) throw std::runtime_error(temp.string() + ": cannot write");
  out << std::setprecision(17);
  return out;
}

void closeAndRename(std::ofstream& out, const fs::path& temp, const fs::path& file) {
  out.flush();
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  out.close();
  fs::rename(temp, file);
}

}  // namespace

std::map<uint32_t, Camera> readColmapCameras(const fs::path& file) {
  LineReader reader(file);
  std::map<uint32_t, Camera> cameras;
  std::string line;
  while (reader.next(line)) {
    std::istringstream in(line);
    Camera c;
    c.id = field<uint32_t>(in, reader, "CAMERA_ID");
    const std::string model = field<std::string>(in, reader, "MODEL");
    try {
      c.model = cameraModelFromName(model);
    } catch (const std::invalid_argument& e) {
      reader.fail(e.what());
    }
    c.width = field<int>(in, reader, "WIDTH");
    c.height = field<int>(in, reader, "HEIGHT");
    if (c.width <= 0 || c.height <= 0) reader.fail("WIDTH and HEIGHT must be positive");
    std::vector<double> params;
    double p = 0;
    while (in >> p) params.push_back(p);
    if (!in.eof()) reader.fail("malformed PARAMS");
    if (params.size() != parameterCount(c.model)) {
      reader.fail(model + " needs " + std::to_string(parameterCount(c.model)) + " PARAMS, got " +
                  std::to_string(params.size()));
    }
    size_t next = 0;
    c.fx = params[next++];
    c.fy = c.model == CameraModel::SIMPLE_PINHOLE ? c.fx : params[next++];
    c.cx = params[next++] - kColmapPixelOffset;
    c.cy = params[next++] - kColmapPixelOffset;
    c.distortion.assign(params.begin() + next, params.end());
    if (!cameras.emplace(c.id, c).second) {
      reader.fail("CAMERA_ID " + std::to_string(c.id) + " appears twice");
    }
  }
  return cameras;
}

std::map<uint32_t, Image> readColmapImages(const fs::path& file) {
  LineReader reader(file);
  std::map<uint32_t, Image> images;
  std::string line;
  while (reader.next(line)) {
    std::istringstream in(line);
    Image image;
    image.id = field<uint32_t>(in, reader, "IMAGE_ID");
    const double qw = field<double>(in, reader, "QW"), qx = field<double>(in, reader, "QX"),
                 qy = field<double>(in, reader, "QY"), qz = field<double>(in, reader, "QZ");
    image.q_cw = Eigen::Quaterniond(qw, qx, qy, qz);
    if (std::abs(image.q_cw.norm() - 1.0) > 1e-3) reader.fail("quaternion is not unit length");
    image.q_cw.normalize();
    image.t_cw.x() = field<double>(in, reader, "TX");
    image.t_cw.y() = field<double>(in, reader, "TY");
    image.t_cw.z() = field<double>(in, reader, "TZ");
    image.camera_id = field<uint32_t>(in, reader, "CAMERA_ID");
    std::getline(in >> std::ws, image.name);
    if (image.name.empty()) reader.fail("missing NAME");
    if (!reader.next(line, true)) reader.fail("missing the keypoint line of image " + image.name);
    std::istringstream points(line);
    double x = 0, y = 0;
    int64_t id = 0;
    while (points >> x) {
      if (!(points >> y >> id)) reader.fail("keypoints must come as X Y POINT3D_ID triples");
      image.points2d.emplace_back(x - kColmapPixelOffset, y - kColmapPixelOffset);
      image.point3d_ids.push_back(id < 0 ? kNoPoint3D : id);
    }
    if (!points.eof()) reader.fail("malformed keypoint line");
    if (!images.emplace(image.id, std::move(image)).second) {
      reader.fail("IMAGE_ID appears twice");
    }
  }
  return images;
}

std::map<uint64_t, Point3D> readColmapPoints(const fs::path& file) {
  LineReader reader(file);
  std::map<uint64_t, Point3D> points;
  std::string line;
  while (reader.next(line)) {
    std::istringstream in(line);
    Point3D p;
    p.id = field<uint64_t>(in, reader, "POINT3D_ID");
    for (int i = 0; i < 3; ++i) p.xyz[i] = field<double>(in, reader, "X Y Z");
    for (int i = 0; i < 3; ++i) {
      const int c = field<int>(in, reader, "R G B");
      if (c < 0 || c > 255) reader.fail("colour outside 0..255");
      p.rgb[i] = static_cast<uint8_t>(c);
    }
    p.error = field<double>(in, reader, "ERROR");
    uint32_t image_id = 0, idx = 0;
    while (in >> image_id) {
      if (!(in >> idx)) reader.fail("track must come as IMAGE_ID POINT2D_IDX pairs");
      p.track.push_back({image_id, idx});
    }
    if (!in.eof()) reader.fail("malformed track");
    if (!points.emplace(p.id, std::move(p)).second) reader.fail("POINT3D_ID appears twice");
  }
  return points;
}

Reconstruction readColmapText(const fs::path& folder) {
  Reconstruction r;
  r.cameras = readColmapCameras(folder / "cameras.txt");
  r.images = readColmapImages(folder / "images.txt");
  if (fs::exists(folder / "points3D.txt")) r.points = readColmapPoints(folder / "points3D.txt");
  try {
    r.checkConsistency();
  } catch (const std::exception& e) {
    throw std::runtime_error(folder.string() + ": inconsistent model: " + e.what());
  }
  return r;
}

void writeColmapText(const Reconstruction& r, const fs::path& folder) {
  fs::create_directories(folder);
  {
    const fs::path file = folder / "cameras.txt", temp = temporaryPathFor(file);
    std::ofstream out = openForWriting(temp);
    out << "# Camera list with one line of data per camera:\n"
           "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
           "# Number of cameras: "
        << r.cameras.size() << "\n";
    for (const auto& [id, c] : r.cameras) {
      out << id << ' ' << cameraModelName(c.model) << ' ' << c.width << ' ' << c.height << ' '
          << c.fx;
      if (c.model != CameraModel::SIMPLE_PINHOLE) out << ' ' << c.fy;
      out << ' ' << c.cx + kColmapPixelOffset << ' ' << c.cy + kColmapPixelOffset;
      for (double d : c.distortion) out << ' ' << d;
      out << '\n';
    }
    closeAndRename(out, temp, file);
  }
  {
    const fs::path file = folder / "images.txt", temp = temporaryPathFor(file);
    std::ofstream out = openForWriting(temp);
    size_t observations = 0;
    for (const auto& [id, image] : r.images) observations += image.numPoints3D();
    out << "# Image list with two lines of data per image:\n"
           "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
           "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
           "# Number of images: "
        << r.images.size() << ", mean observations per image: "
        << (r.images.empty() ? 0.0 : static_cast<double>(observations) / r.images.size()) << "\n";
    for (const auto& [id, image] : r.images) {
      const Eigen::Quaterniond& q = image.q_cw;
      const double sign = q.w() < 0 ? -1.0 : 1.0;  // COLMAP writes qw >= 0
      out << id << ' ' << sign * q.w() << ' ' << sign * q.x() << ' ' << sign * q.y() << ' '
          << sign * q.z() << ' ' << image.t_cw.x() << ' ' << image.t_cw.y() << ' ' << image.t_cw.z()
          << ' ' << image.camera_id << ' ' << image.name << '\n';
      for (size_t k = 0; k < image.points2d.size(); ++k) {
        if (k > 0) out << ' ';
        out << image.points2d[k].x() + kColmapPixelOffset << ' '
            << image.points2d[k].y() + kColmapPixelOffset << ' ' << image.point3d_ids[k];
      }
      out << '\n';
    }
    closeAndRename(out, temp, file);
  }
  {
    const fs::path file = folder / "points3D.txt", temp = temporaryPathFor(file);
    std::ofstream out = openForWriting(temp);
    out << "# 3D point list with one line of data per point:\n"
           "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
           "# Number of points: "
        << r.points.size() << ", mean track length: " << r.meanTrackLength() << "\n";
    for (const auto& [id, p] : r.points) {
      out << id << ' ' << p.xyz.x() << ' ' << p.xyz.y() << ' ' << p.xyz.z() << ' ' << int(p.rgb[0])
          << ' ' << int(p.rgb[1]) << ' ' << int(p.rgb[2]) << ' ' << p.error;
      for (const auto& e : p.track) out << ' ' << e.image_id << ' ' << e.point2d_idx;
      out << '\n';
    }
    closeAndRename(out, temp, file);
  }
}

}  // namespace auv::recon::scene
