#include "auv/recon/texture/textured_model.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon::texture {

void TexturedModel::validate() const {
  if (face_uvs.size() != faces.size() || face_page.size() != faces.size()) {
    throw std::invalid_argument("textured model: " + std::to_string(faces.size()) + " faces but " +
                                std::to_string(face_uvs.size()) + " uv triples and " +
                                std::to_string(face_page.size()) + " page indices");
  }
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (faces[f](k) < 0 || static_cast<size_t>(faces[f](k)) >= vertices.size()) {
        throw std::invalid_argument("textured model: face " + std::to_string(f) +
                                    " has vertex index " + std::to_string(faces[f](k)));
      }
    }
    if (face_page[f] < 0 || static_cast<size_t>(face_page[f]) >= pages.size()) {
      throw std::invalid_argument("textured model: face " + std::to_string(f) + " on page " +
                                  std::to_string(face_page[f]) + " of " +
                                  std::to_string(pages.size()));
    }
  }
}

void writeObj(const TexturedModel& model, const fs::path& folder, const std::string& stem) {
  model.validate();
  fs::create_directories(folder);
  std::ostringstream mtl;
  mtl << "# auv-inspect textured model: one material per atlas page\n";
  for (size_t p = 0; p < model.pages.size(); ++p) {
    const std::string png = stem + "_" + std::to_string(p) + ".png";
    const fs::path file = folder / png;
    const fs::path temporary = temporaryPathFor(file).string() + ".png";
    if (!cv::imwrite(temporary.string(), model.pages[p])) {
      throw std::runtime_error(file.string() + ": cannot write the atlas page");
    }
    fs::rename(temporary, file);
    mtl << "newmtl page_" << p << "\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd " << png
        << "\n\n";
  }
  writeFileAtomically(folder / (stem + ".mtl"), mtl.str());

  std::ostringstream obj;
  obj.precision(9);
  obj << "# auv-inspect textured model: " << model.vertices.size() << " vertices, "
      << model.faces.size() << " faces, " << model.pages.size() << " atlas pages\n";
  obj << "mtllib " << stem << ".mtl\n";
  for (const auto& v : model.vertices) obj << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  obj.precision(7);
  for (const auto& uvs : model.face_uvs) {
    for (const auto& uv : uvs) obj << "vt " << uv.x() << ' ' << uv.y() << '\n';
  }
  // Faces grouped by page (one usemtl each); texture coordinates are per face corner.
  std::map<int, std::vector<size_t>> faces_of_page;
  for (size_t f = 0; f < model.faces.size(); ++f) faces_of_page[model.face_page[f]].push_back(f);
  for (const auto& [page, faces] : faces_of_page) {
    obj << "usemtl page_" << page << '\n';
    for (size_t f : faces) {
      obj << 'f';
      for (int k = 0; k < 3; ++k) obj << ' ' << model.faces[f](k) + 1 << '/' << 3 * f + k + 1;
      obj << '\n';
    }
  }
  writeFileAtomically(folder / (stem + ".obj"), obj.str());
}

namespace {

[[noreturn]] void objError(const fs::path& file, size_t line, const std::string& what) {
  throw std::runtime_error(file.string() + ":" + std::to_string(line) + ": " + what);
}

/// Materials of an MTL file: name -> texture image path.
std::map<std::string, fs::path> readMtl(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open the material file");
  std::map<std::string, fs::path> materials;
  std::string line, current;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "newmtl") {
      fields >> current;
    } else if (key == "map_Kd") {
      std::string texture;
      std::getline(fields >> std::ws, texture);
      while (!texture.empty() && (texture.back() == '\r' || texture.back() == ' '))
        texture.pop_back();
      materials[current] = file.parent_path() / texture;
    }
  }
  return materials;
}

}  // namespace

TexturedModel readObj(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  TexturedModel model;
  std::vector<Eigen::Vector2f> uvs;
  std::map<std::string, fs::path> materials;
  std::map<std::string, int> page_of_material;
  int page = -1;
  std::string line;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "v") {
      Eigen::Vector3d v;
      if (!(fields >> v.x() >> v.y() >> v.z())) objError(file, number, "bad vertex");
      model.vertices.push_back(v);
    } else if (key == "vt") {
      Eigen::Vector2f uv;
      if (!(fields >> uv.x() >> uv.y())) objError(file, number, "bad texture coordinate");
      uvs.push_back(uv);
    } else if (key == "mtllib") {
      std::string name;
      std::getline(fields >> std::ws, name);
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      for (const auto& [material, texture] : readMtl(file.parent_path() / name)) {
        materials[material] = texture;
      }
    } else if (key == "usemtl") {
      std::string material;
      fields >> material;
      const auto known = page_of_material.find(material);
      if (known != page_of_material.end()) {
        page = known->second;
        continue;
      }
      const auto it = materials.find(material);
      if (it == materials.end())
        objError(file, number, "material '" + material + "' not in the MTL");
      cv::Mat3b image = cv::imread(it->second.string(), cv::IMREAD_COLOR);
      if (image.empty()) objError(file, number, it->second.string() + ": cannot read the texture");
      page = static_cast<int>(model.pages.size());
      model.pages.push_back(image);
      page_of_material[material] = page;
    } else if (key == "f") {
      Eigen::Vector3i face;
      std::array<Eigen::Vector2f, 3> face_uv;
      std::string corner;
      int k = 0;
      while (fields >> corner) {
        if (k == 3) objError(file, number, "only triangles are supported");
        int v = 0, t = 0;
        if (std::sscanf(corner.c_str(), "%d/%d", &v, &t) != 2) {
          objError(file, number, "face corner '" + corner + "' has no texture coordinate");
        }
        if (v < 0) v += static_cast<int>(model.vertices.size()) + 1;
        if (t < 0) t += static_cast<int>(uvs.size()) + 1;
        if (v < 1 || static_cast<size_t>(v) > model.vertices.size() || t < 1 ||
            static_cast<size_t>(t) > uvs.size()) {
          objError(file, number, "index out of range in '" + corner + "'");
        }
        face(k) = v - 1;
        face_uv[k] = uvs[t - 1];
        ++k;
      }
      if (k != 3) objError(file, number, "a face needs 3 corners");
      if (page < 0) objError(file, number, "face before any usemtl");
      model.faces.push_back(face);
      model.face_uvs.push_back(face_uv);
      model.face_page.push_back(page);
    }
  }
  model.validate();
  return model;
}

Rendering renderTexturedModel(const TexturedModel& model, const ViewGeometry& view,
                              const cv::Vec3b& background) {
  const RasterBuffers buffers = rasterize(model.vertices, model.faces, view);
  Rendering rendering;
  rendering.image = cv::Mat3b(view.height(), view.width(), background);
  rendering.mask = cv::Mat1b(view.height(), view.width(), uint8_t{0});
  rendering.depth = buffers.depth;
#pragma omp parallel for schedule(dynamic, 16)
  for (int y = 0; y < view.height(); ++y) {
    for (int x = 0; x < view.width(); ++x) {
      const int f = buffers.face(y, x);
      if (f < 0) continue;
      const Eigen::Vector3d w =
          barycentricAt(model.vertices, model.faces[f], view, Eigen::Vector2d(x, y));
      const Eigen::Vector3f c = sampleFace(model, f, w);
      rendering.image(y, x) =
          cv::Vec3b(cv::saturate_cast<uint8_t>(c(0)), cv::saturate_cast<uint8_t>(c(1)),
                    cv::saturate_cast<uint8_t>(c(2)));
      rendering.mask(y, x) = 255;
    }
  }
  return rendering;
}

Eigen::Vector3f sampleFace(const TexturedModel& model, int face, const Eigen::Vector3d& weights) {
  const auto& uv = model.face_uvs[face];
  const Eigen::Vector2f t = static_cast<float>(weights(0)) * uv[0] +
                            static_cast<float>(weights(1)) * uv[1] +
                            static_cast<float>(weights(2)) * uv[2];
  const cv::Mat3b& page = model.pages[model.face_page[face]];
  // Texel centres at (i + 0.5) / size; v counts from the bottom.
  return sampleBilinear(page, t.x() * page.cols - 0.5, (1.0 - t.y()) * page.rows - 0.5);
}

double psnr(const cv::Mat3b& image, const cv::Mat3b& reference, const cv::Mat1b& mask) {
  if (image.size() != reference.size() || (!mask.empty() && mask.size() != image.size())) {
    throw std::invalid_argument("psnr: images of different sizes");
  }
  double squared = 0;
  size_t count = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (!mask.empty() && mask(y, x) == 0) continue;
      for (int c = 0; c < 3; ++c) {
        const double d = static_cast<double>(image(y, x)[c]) - reference(y, x)[c];
        squared += d * d;
      }
      count += 3;
    }
  }
  if (count == 0) throw std::invalid_argument("psnr: no pixel to compare");
  const double mse = squared / count;
  if (mse == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace auv::recon::texture
