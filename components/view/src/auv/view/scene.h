#pragma once
// What the page shows, converted on the server: a JSON manifest of layers (/api/scene) and the
// binary buffers and files the layers point at. The page never names a path of the folder:
// every byte it can fetch is a route of this map (README.md, "Security").

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace auv::view {

/// Typed arrays packed into one little-endian blob, each 4-byte aligned so the page can view
/// them in place (new Float32Array(buffer, offset, count)).
class BufferBuilder {
 public:
  void addFloat32(const std::string& name, const std::vector<float>& values, int item_size);
  void addUint32(const std::string& name, const std::vector<uint32_t>& values, int item_size);
  void addUint8(const std::string& name, const std::vector<uint8_t>& values, int item_size);
  /// {name: {offset, count (items), type: "f32"|"u32"|"u8", itemSize}}
  const nlohmann::json& layout() const { return layout_; }
  std::string& bytes() { return bytes_; }
  bool empty() const { return bytes_.empty(); }

 private:
  void add(const std::string& name, const void* data, size_t bytes, size_t items, const char* type,
           int item_size);
  std::string bytes_;
  nlohmann::json layout_ = nlohmann::json::object();
};

struct Blob {
  std::string content_type;
  std::string bytes;
};

struct Scene {
  /// {kind, name, folder, frame, layers: [...], live, notes: [...]}
  nlohmann::json manifest = nlohmann::json::object();
  std::map<std::string, Blob> blobs;                   ///< route ("/data/...") -> bytes
  std::map<std::string, std::filesystem::path> files;  ///< route -> a file of the folder

  /// Appends `layer` (its "id" must be unique) with "url" and "arrays" of `buffer`'s blob.
  void addLayer(nlohmann::json layer, BufferBuilder&& buffer);
  /// A file the page may fetch (a texture), served at the returned route.
  std::string addFile(const std::filesystem::path& file);
  /// Appends a line to manifest["notes"] (what is missing and the command that makes it).
  void note(const std::string& text);
};

/// Triangle and point budgets and the frame of the data (README.md, "Levels of detail").
struct SceneOptions {
  size_t default_triangles = 300000;  ///< the finest level the page picks by itself ("auto")
  size_t min_triangles = 10000;       ///< levels stop at the first one this small
  size_t max_points = 1000000;        ///< clouds are thinned to this many points
};

}  // namespace auv::view
