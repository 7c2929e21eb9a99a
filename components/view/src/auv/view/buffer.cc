#include <cstring>

#include "auv/view/scene.h"

namespace auv::view {

void BufferBuilder::add(const std::string& name, const void* data, size_t bytes, size_t items,
                        const char* type, int item_size) {
  const size_t offset = bytes_.size();
  bytes_.append(static_cast<const char*>(data), bytes);
  bytes_.resize((bytes_.size() + 3) / 4 * 4, '\0');  // the next typed view stays aligned
  layout_[name] = {{"offset", offset}, {"count", items}, {"type", type}, {"itemSize", item_size}};
}

void BufferBuilder::addFloat32(const std::string& name, const std::vector<float>& values,
                               int item_size) {
  add(name, values.data(), values.size() * sizeof(float), values.size() / item_size, "f32",
      item_size);
}

void BufferBuilder::addUint32(const std::string& name, const std::vector<uint32_t>& values,
                              int item_size) {
  add(name, values.data(), values.size() * sizeof(uint32_t), values.size() / item_size, "u32",
      item_size);
}

void BufferBuilder::addUint8(const std::string& name, const std::vector<uint8_t>& values,
                             int item_size) {
  add(name, values.data(), values.size(), values.size() / item_size, "u8", item_size);
}

void Scene::addLayer(nlohmann::json layer, BufferBuilder&& buffer) {
  const std::string route = "/data/" + layer.at("id").get<std::string>() + ".bin";
  layer["url"] = route;
  layer["arrays"] = buffer.layout();
  layer["bytes"] = buffer.bytes().size();
  blobs[route] = Blob{"application/octet-stream", std::move(buffer.bytes())};
  manifest["layers"].push_back(std::move(layer));
}

std::string Scene::addFile(const std::filesystem::path& file) {
  const std::string extension = file.extension().string();
  const std::string route = "/data/file/" + std::to_string(files.size()) + extension;
  files[route] = file;
  return route;
}

void Scene::note(const std::string& text) { manifest["notes"].push_back(text); }

}  // namespace auv::view
