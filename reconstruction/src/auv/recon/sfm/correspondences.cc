#include "auv/recon/sfm/correspondences.h"

#include <algorithm>
#include <iterator>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace auv::recon::sfm {

void SfmInput::check() const {
  for (const auto& [id, camera] : cameras) {
    if (camera.id != id) {
      throw std::invalid_argument("camera " + std::to_string(id) + " carries id " +
                                  std::to_string(camera.id));
    }
    if (!(camera.fx > 0) || !(camera.fy > 0)) {
      throw std::invalid_argument("camera " + std::to_string(id) + ": focal length must be > 0");
    }
    if (camera.hasDistortion()) {
      throw std::invalid_argument("camera " + std::to_string(id) +
                                  " has lens distortion: SfM expects undistorted images");
    }
  }
  std::map<uint32_t, size_t> keypoints;
  for (const View& view : views) {
    if (!cameras.count(view.camera_id)) {
      throw std::invalid_argument("image " + std::to_string(view.id) + " ('" + view.name +
                                  "') refers to unknown camera " + std::to_string(view.camera_id));
    }
    if (!keypoints.emplace(view.id, view.keypoints.size()).second) {
      throw std::invalid_argument("image id " + std::to_string(view.id) + " ('" + view.name +
                                  "') is used twice");
    }
  }
  for (const ViewPair& pair : pairs) {
    const std::string name =
        "pair (" + std::to_string(pair.image_a) + ", " + std::to_string(pair.image_b) + ")";
    if (pair.image_a == pair.image_b) throw std::invalid_argument(name + ": same image twice");
    auto a = keypoints.find(pair.image_a), b = keypoints.find(pair.image_b);
    if (a == keypoints.end() || b == keypoints.end()) {
      throw std::invalid_argument(name + ": unknown image");
    }
    for (const auto& [ka, kb] : pair.matches) {
      if (ka >= a->second || kb >= b->second) {
        throw std::invalid_argument(name + ": match (" + std::to_string(ka) + ", " +
                                    std::to_string(kb) + ") beyond the keypoints (" +
                                    std::to_string(a->second) + ", " + std::to_string(b->second) +
                                    ")");
      }
    }
  }
}

namespace {
uint64_t find(std::vector<uint64_t>& parent, uint64_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];  // path halving
    x = parent[x];
  }
  return x;
}
}  // namespace

Tracks Tracks::build(const SfmInput& input) {
  // Nodes: every keypoint of every image, numbered image by image.
  std::unordered_map<uint32_t, uint64_t> offset;
  std::vector<uint32_t> node_image;
  uint64_t nodes = 0;
  for (const View& view : input.views) {
    offset[view.id] = nodes;
    nodes += view.keypoints.size();
    node_image.insert(node_image.end(), view.keypoints.size(), view.id);
  }
  std::vector<uint64_t> parent(nodes);
  std::iota(parent.begin(), parent.end(), 0);
  // Images of each root's component (sorted), merged small into large.
  std::unordered_map<uint64_t, std::vector<uint32_t>> images;
  auto imagesOf = [&](uint64_t root) -> std::vector<uint32_t>& {
    auto [it, inserted] = images.try_emplace(root);
    if (inserted) it->second.push_back(node_image[root]);
    return it->second;
  };
  std::vector<size_t> order(input.pairs.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return input.pairs[x].matches.size() > input.pairs[y].matches.size();
  });
  Tracks tracks;
  std::vector<uint8_t> matched(nodes, 0);
  for (size_t index : order) {
    const ViewPair& pair = input.pairs[index];
    const uint64_t oa = offset.at(pair.image_a), ob = offset.at(pair.image_b);
    for (const auto& [ka, kb] : pair.matches) {
      const uint64_t ra = find(parent, oa + ka), rb = find(parent, ob + kb);
      if (ra == rb) continue;
      std::vector<uint32_t>& ia = imagesOf(ra);
      std::vector<uint32_t>& ib = imagesOf(rb);
      std::vector<uint32_t> merged;
      merged.reserve(ia.size() + ib.size());
      std::set_union(ia.begin(), ia.end(), ib.begin(), ib.end(), std::back_inserter(merged));
      if (merged.size() != ia.size() + ib.size()) {
        ++tracks.stats_.conflicting_matches;
        continue;
      }
      matched[oa + ka] = matched[ob + kb] = 1;
      const uint64_t root = std::min(ra, rb), child = std::max(ra, rb);
      parent[child] = root;
      images[root] = std::move(merged);
      images.erase(child);
    }
  }

  std::unordered_map<uint64_t, std::vector<scene::TrackElement>> components;
  for (const View& view : input.views) {
    const uint64_t o = offset.at(view.id);
    for (uint32_t k = 0; k < view.keypoints.size(); ++k) {
      if (matched[o + k]) components[find(parent, o + k)].push_back({view.id, k});
    }
  }
  for (const View& view : input.views) {
    tracks.keypoint_tracks_[view.id].assign(view.keypoints.size(), kNoTrack);
  }
  // Deterministic track ids: components in the order of their root node.
  std::vector<uint64_t> roots;
  roots.reserve(components.size());
  for (const auto& [root, elements] : components) roots.push_back(root);
  std::sort(roots.begin(), roots.end());
  for (uint64_t root : roots) {
    std::vector<scene::TrackElement>& elements = components[root];
    const int64_t id = static_cast<int64_t>(tracks.tracks_.size());
    for (const auto& e : elements) tracks.keypoint_tracks_[e.image_id][e.point2d_idx] = id;
    tracks.stats_.observations += elements.size();
    tracks.tracks_.push_back(std::move(elements));
  }
  tracks.stats_.tracks = tracks.tracks_.size();
  return tracks;
}

int64_t Tracks::trackOf(uint32_t image_id, uint32_t keypoint) const {
  auto it = keypoint_tracks_.find(image_id);
  if (it == keypoint_tracks_.end() || keypoint >= it->second.size()) return kNoTrack;
  return it->second[keypoint];
}

const std::vector<int64_t>& Tracks::tracksOfImage(uint32_t image_id) const {
  auto it = keypoint_tracks_.find(image_id);
  if (it == keypoint_tracks_.end()) {
    throw std::out_of_range("tracks: no image " + std::to_string(image_id));
  }
  return it->second;
}

}  // namespace auv::recon::sfm
