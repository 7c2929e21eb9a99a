#pragma once
// The survey's textured model (textured/model.obj, reconstruction/src/auv/recon/texture) and its
// levels of detail (README.md, "Levels of detail").

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace auv::view {

/// An indexed mesh: one vertex per distinct (position, texture coordinate) pair of the OBJ, so
/// it draws with one index buffer; triangles grouped by material (one atlas page each).
struct TexturedMesh {
  struct Group {
    size_t first_index = 0, index_count = 0;  ///< a range of `index`
    std::string material;
    std::filesystem::path texture;  ///< the material's map_Kd, empty when none
  };
  std::vector<float> position;  ///< xyz per vertex
  std::vector<float> uv;        ///< uv per vertex (0, 0 where the OBJ gives none)
  std::vector<uint8_t> color;   ///< sRGB per vertex, only on levels coloured by the atlas
  std::vector<uint32_t> index;  ///< three per triangle
  std::vector<Group> groups;
  size_t triangles() const { return index.size() / 3; }
};

/// Reads the OBJ subset the texture stage writes and other tools share: `v`, `vt`,
/// `f v[/vt[/vn]]` (polygons fanned, negative indices), `usemtl`, `mtllib` with `newmtl` and
/// `map_Kd`. The readers of auv_reconstruction are not exported to other packages, hence this
/// one. Throws config::ConfigError naming file:line for what it cannot read, and a texture that
/// is missing or outside the model's folder.
TexturedMesh readObj(const std::filesystem::path& file);

struct MeshLevel {
  TexturedMesh mesh;  ///< vertices compacted to those the level uses
  float error = 0;    ///< meshoptimizer's relative error of this level (0 for the original)
};

/// The original, then levels of about half the previous triangles each (meshoptimizer's
/// edge collapse, per material so every triangle keeps its atlas page, group borders locked so
/// pages do not crack apart, texture seams kept), down to about `min_triangles`. Where the
/// atlas pins the surface (a patch per face, as `auv recon texture` writes, or charts so small
/// that every vertex is on a seam) the coarser levels are simplified without it and carry its
/// colours per vertex (bakeVertexColours). Stops early when a level would remove less than
/// 20 % (tiny meshes).
std::vector<MeshLevel> buildLevels(const TexturedMesh& mesh, size_t min_triangles);

/// `mesh` welded by position (one vertex where the atlas's seams had several), one group
/// without a texture, each vertex coloured by the mean of the atlas around its corners. A page
/// that cannot be decoded leaves its vertices grey (named on stderr).
TexturedMesh bakeVertexColours(const TexturedMesh& mesh);

/// A part of a level the page draws as its own object, so the parts off screen are skipped
/// (frustum culling is per object): its triangles as ranges of the level's index, per page.
struct Tile {
  std::vector<TexturedMesh::Group> groups;
  float center[3] = {0, 0, 0};
  float radius = 0;
};

/// Reorders `mesh.index` so the triangles of each tile are contiguous, tile by tile and page by
/// page within a tile, on a grid of up to 16 x 16 tiles over the mesh's two longest extents
/// (by triangle centroid), about `triangles_per_tile` each (one tile for a small mesh).
/// `mesh.groups` becomes the tiles' groups in that order. Partitions only: no new vertices, no
/// cracks.
std::vector<Tile> tileMesh(TexturedMesh& mesh, size_t triangles_per_tile);

}  // namespace auv::view
