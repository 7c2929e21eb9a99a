#include <meshoptimizer.h>

#include "auv/view/mesh.h"

namespace auv::view {

namespace {

/// `mesh` with only the vertices `index` uses, renumbered in first-use order (what the GPU
/// fetches stays local, and a coarse level does not carry the original's vertex buffer).
TexturedMesh compact(const TexturedMesh& mesh, const std::vector<uint32_t>& index,
                     const std::vector<TexturedMesh::Group>& groups) {
  TexturedMesh out;
  out.groups = groups;
  std::vector<uint32_t> remap(mesh.position.size() / 3, UINT32_MAX);
  out.index.reserve(index.size());
  for (uint32_t v : index) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.position.size() / 3);
      out.position.insert(out.position.end(), mesh.position.begin() + 3 * v,
                          mesh.position.begin() + 3 * v + 3);
      out.uv.insert(out.uv.end(), mesh.uv.begin() + 2 * v, mesh.uv.begin() + 2 * v + 2);
    }
    out.index.push_back(remap[v]);
  }
  return out;
}

}  // namespace

std::vector<MeshLevel> buildLevels(const TexturedMesh& mesh, size_t min_triangles) {
  std::vector<MeshLevel> levels;
  levels.push_back({mesh, 0.f});
  while (levels.back().mesh.triangles() > min_triangles) {
    const TexturedMesh& previous = levels.back().mesh;
    std::vector<uint32_t> index;
    std::vector<TexturedMesh::Group> groups;
    float worst = 0;
    for (const auto& group : previous.groups) {
      const size_t target = std::max<size_t>(group.index_count / 2 / 3 * 3, 3);
      std::vector<uint32_t> out(group.index_count);
      float error = 0;
      // Target error 5 % of the extent: the triangle count decides, not the error bound.
      const size_t count =
          meshopt_simplify(out.data(), previous.index.data() + group.first_index, group.index_count,
                           previous.position.data(), previous.position.size() / 3,
                           3 * sizeof(float), target, 0.05f, meshopt_SimplifyLockBorder, &error);
      worst = std::max(worst, error);
      TexturedMesh::Group g = group;
      g.first_index = index.size();
      g.index_count = count;
      index.insert(index.end(), out.begin(), out.begin() + count);
      if (count > 0) groups.push_back(g);
    }
    if (index.size() > previous.index.size() * 8 / 10) break;  // no longer worth a level
    levels.push_back({compact(previous, index, groups), worst});
  }
  return levels;
}

}  // namespace auv::view
