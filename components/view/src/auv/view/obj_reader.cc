#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <unordered_map>

#include "auv/config/errors.h"
#include "auv/view/mesh.h"

namespace auv::view {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& file, size_t line, const std::string& what) {
  throw config::ConfigError(file.string() + ":" + std::to_string(line) + ": " + what);
}

/// map_Kd of each material of an MTL file, made absolute and checked to lie in `folder`.
std::map<std::string, fs::path> readMtl(const fs::path& mtl, const fs::path& folder) {
  std::ifstream in(mtl);
  if (!in) throw config::ConfigError(mtl.string() + ": cannot read (named by mtllib)");
  std::map<std::string, fs::path> textures;
  std::string line, current;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind("newmtl ", 0) == 0) {
      current = line.substr(7);
      textures[current];
    } else if (line.rfind("map_Kd ", 0) == 0) {
      if (current.empty()) fail(mtl, number, "map_Kd before any newmtl");
      const fs::path texture = fs::weakly_canonical(folder / line.substr(7));
      const fs::path root = fs::weakly_canonical(folder);
      const auto rel = texture.lexically_relative(root);
      // The page may fetch textures only: never a file outside the model's own folder.
      if (rel.empty() || *rel.begin() == "..") {
        fail(mtl, number, "texture '" + line.substr(7) + "' lies outside " + root.string());
      }
      if (!fs::is_regular_file(texture)) {
        fail(mtl, number, "texture '" + line.substr(7) + "' not found (" + texture.string() + ")");
      }
      textures[current] = texture;
    }
  }
  return textures;
}

/// One `v/vt/vn` corner: 0-based position and texture indices (-1: none).
bool parseCorner(const char*& s, long positions, long uvs, long& v, long& vt) {
  char* end = nullptr;
  v = std::strtol(s, &end, 10);
  if (end == s) return false;
  v = v < 0 ? positions + v : v - 1;
  s = end;
  vt = -1;
  if (*s == '/') {
    ++s;
    if (*s != '/') {
      const long t = std::strtol(s, &end, 10);
      if (end == s) return false;
      vt = t < 0 ? uvs + t : t - 1;
      s = end;
    }
    if (*s == '/') {  // a normal index: not used (textured models are drawn unlit)
      ++s;
      std::strtol(s, &end, 10);
      s = end;
    }
  }
  return v >= 0 && v < positions && vt < uvs;
}

}  // namespace

TexturedMesh readObj(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw config::ConfigError(file.string() + ": cannot read");
  std::vector<float> positions, uvs;
  std::map<std::string, fs::path> textures;
  std::vector<std::string> materials = {""};  // index 0: triangles before any usemtl
  std::vector<std::vector<uint32_t>> per_material(1);
  std::unordered_map<uint64_t, uint32_t> vertex_of;  // (v, vt + 1) -> vertex
  TexturedMesh mesh;
  size_t current = 0, number = 0;
  std::string line;
  std::vector<uint32_t> face;
  while (std::getline(in, line)) {
    ++number;
    const char* s = line.c_str();
    if (s[0] == 'v' && (s[1] == ' ' || s[1] == 't')) {
      const bool uv = s[1] == 't';
      s += 2;
      for (int i = 0; i < (uv ? 2 : 3); ++i) {
        char* end = nullptr;
        const float value = std::strtof(s, &end);
        if (end == s)
          fail(file, number, std::string("expected ") + (uv ? "'vt u v'" : "'v x y z'"));
        (uv ? uvs : positions).push_back(value);
        s = end;
      }
    } else if (s[0] == 'f' && s[1] == ' ') {
      s += 2;
      face.clear();
      const long np = static_cast<long>(positions.size() / 3),
                 nt = static_cast<long>(uvs.size() / 2);
      while (true) {
        while (*s == ' ' || *s == '\t' || *s == '\r') ++s;
        if (*s == '\0') break;
        long v = 0, vt = 0;
        if (!parseCorner(s, np, nt, v, vt))
          fail(file, number, "bad face corner (index out of range or malformed)");
        const uint64_t key = (static_cast<uint64_t>(v) << 32) | static_cast<uint64_t>(vt + 1);
        auto [it, added] =
            vertex_of.try_emplace(key, static_cast<uint32_t>(mesh.position.size() / 3));
        if (added) {
          mesh.position.insert(mesh.position.end(), positions.begin() + 3 * v,
                               positions.begin() + 3 * v + 3);
          mesh.uv.push_back(vt < 0 ? 0.f : uvs[2 * vt]);
          mesh.uv.push_back(vt < 0 ? 0.f : uvs[2 * vt + 1]);
        }
        face.push_back(it->second);
      }
      if (face.size() < 3) fail(file, number, "a face with fewer than 3 corners");
      for (size_t i = 2; i < face.size(); ++i) {
        per_material[current].insert(per_material[current].end(), {face[0], face[i - 1], face[i]});
      }
    } else if (line.rfind("usemtl ", 0) == 0) {
      std::string name = line.substr(7);
      if (!name.empty() && name.back() == '\r') name.pop_back();
      size_t i = 0;
      while (i < materials.size() && materials[i] != name) ++i;
      if (i == materials.size()) {
        materials.push_back(name);
        per_material.emplace_back();
      }
      current = i;
    } else if (line.rfind("mtllib ", 0) == 0) {
      std::string name = line.substr(7);
      if (!name.empty() && name.back() == '\r') name.pop_back();
      const auto more = readMtl(file.parent_path() / name, file.parent_path());
      textures.insert(more.begin(), more.end());
    }
  }
  for (size_t m = 0; m < materials.size(); ++m) {
    if (per_material[m].empty()) continue;
    TexturedMesh::Group group;
    group.first_index = mesh.index.size();
    group.index_count = per_material[m].size();
    group.material = materials[m];
    if (!materials[m].empty()) {
      const auto it = textures.find(materials[m]);
      if (it == textures.end()) {
        throw config::ConfigError(file.string() + ": usemtl '" + materials[m] +
                                  "' names no material of its mtllib");
      }
      group.texture = it->second;
    }
    mesh.index.insert(mesh.index.end(), per_material[m].begin(), per_material[m].end());
    mesh.groups.push_back(group);
  }
  if (mesh.index.empty()) throw config::ConfigError(file.string() + ": no faces");
  return mesh;
}

}  // namespace auv::view
