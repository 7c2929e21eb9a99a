// `breakwater`: the harbour structure of the paper's Figs. 3-5 (Sant Feliu de Guixols): a row
// of concrete blocks, each 14.5 m long and 12 m wide, standing on a ~10 m sandy seabed and
// rising above the surface, with gaps of 2-4 m between them. The query crosses the row.
#include <algorithm>
#include <cmath>

#include "auv/sim/worldgen/world_builders.h"

namespace auv::sim::worldgen {

using Eigen::Vector2f;
using Eigen::Vector3d;
using Eigen::Vector3f;

GeneratedWorld buildBreakwater(const WorldGenOptions& options) {
  const DetailScale scale(options.detail);
  LayoutRandom random(options.seed, "breakwater");

  constexpr int kBlocks = 5;
  constexpr float kBlockLength = 14.5f;  // m, along the row (paper, Fig. 3)
  constexpr float kBlockWidth = 12.0f;   // m, across the row
  constexpr float kSeabedZ = -10.0f;
  constexpr float kTopZ = 1.5f;  // m above the surface
  constexpr float kQueryZ = -4.0f;

  // Gaps of 2-4 m; one narrow (2.0-2.4 m) and one wide (3.5-4 m) in every layout.
  std::vector<float> gaps(kBlocks - 1);
  for (float& gap : gaps) gap = random.uniform(2.0f, 4.0f);
  const int narrow = random.integer(0, kBlocks - 2);
  const int wide = (narrow + random.integer(1, kBlocks - 2)) % (kBlocks - 1);
  gaps[narrow] = random.uniform(2.0f, 2.4f);
  gaps[wide] = random.uniform(3.5f, 4.0f);

  // The row runs east-west (mesh y), blocks shifted slightly north-south as if set by a crane.
  float row_length = kBlocks * kBlockLength;
  for (float gap : gaps) row_length += gap;
  WorldDraft draft;
  GeneratedWorld& world = draft.world;
  float y = -0.5f * row_length;
  std::vector<Eigen::AlignedBox3f> blocks;
  for (int i = 0; i < kBlocks; ++i) {
    const float shift = random.uniform(-0.4f, 0.4f);
    blocks.emplace_back(Vector3f(-0.5f * kBlockWidth + shift, y, kSeabedZ - 1.0f),
                        Vector3f(0.5f * kBlockWidth + shift, y + kBlockLength, kTopZ));
    y += kBlockLength + (i < kBlocks - 1 ? gaps[i] : 0.0f);
  }
  for (const Eigen::AlignedBox3f& box : blocks) {
    std::vector<SurfaceGrid> faces =
        buildBlock(box, scale.block_spacing, Material::CONCRETE, scale.structure_texel);
    for (SurfaceGrid& face : faces) draft.grids.push_back(std::move(face));
    const Vector3d lo = box.min().cast<double>(), hi = box.max().cast<double>();
    const Vector3d a = meshToNed(lo), b = meshToNed(hi);
    world.layout.blocks.emplace_back(a.cwiseMin(b), a.cwiseMax(b));
  }

  world.name = "breakwater";
  world.description =
      "A row of five 14.5 m x 12 m concrete blocks with 2-4 m gaps on a 10 m sandy seabed "
      "(paper Figs. 3-5); cross from the north side of the row to the south side and back.";
  world.seabed_depth = -kSeabedZ;
  world.visibility = 6.0;

  // Start north of the middle block, goal south of it: the straight line runs into the block.
  const int middle = kBlocks / 2;
  const double middle_y = blocks[middle].center().y();
  const double clear_x = 0.5 * kBlockWidth + 18.0;
  const Vector3d start(clear_x, middle_y, kQueryZ), goal(-clear_x, middle_y, kQueryZ);
  world.start_position = meshToNed(start);
  world.start_yaw_deg = 180.0;  // facing south, towards the row
  world.queries = {meshQuery("cross", goal, 2.0), meshQuery("cross_back", start, 2.0)};
  // Round the west end of the row, with room to spare.
  const double around_y = 0.5 * row_length + 8.0;
  const std::vector<Vector3d> route{start, Vector3d(clear_x, around_y, kQueryZ),
                                    Vector3d(-clear_x, around_y, kQueryZ), goal};
  world.layout.routes = {meshRoute(route), meshRoute({route.rbegin(), route.rend()})};
  world.layout.query_depth = -kQueryZ;

  SeabedSpec seabed = seabedSpec(kSeabedZ, 0.3f, random, scale);
  seabed.covered = nullptr;
  Eigen::AlignedBox2f area;
  for (const auto& box : blocks) area.extend(box.min().head<2>()).extend(box.max().head<2>());
  area.extend(Vector2f(start.x(), start.y())).extend(Vector2f(goal.x(), goal.y()));
  seabed.area = Eigen::AlignedBox2f(area.min() - Vector2f(12, 20), area.max() + Vector2f(12, 20));
  // Sand hidden under the blocks is left out (0.5 m inside their walls).
  seabed.covered = [&blocks](const Vector2f& xy) {
    for (const auto& box : blocks) {
      const Eigen::AlignedBox2f inner(box.min().head<2>() + Vector2f::Constant(0.5f),
                                      box.max().head<2>() - Vector2f::Constant(0.5f));
      if (inner.contains(xy)) return true;
    }
    return false;
  };
  draft.grids.push_back(buildSeabed(seabed));

  // Riprap: a few fallen stones along the foot of the blocks, far below the query depth.
  for (int i = 0; i < 14; ++i) {
    const auto& box = blocks[random.integer(0, kBlocks - 1)];
    const float side = random.integer(0, 1) ? 1.0f : -1.0f;
    const Vector2f xy(box.center().x() + side * (0.5f * kBlockWidth + random.uniform(0.8f, 3.5f)),
                      random.uniform(box.min().y(), box.max().y()));
    const float radius = random.uniform(0.5f, 1.3f), height = random.uniform(0.4f, 1.2f);
    const uint64_t seed = random.next();
    draft.grids.push_back(
        buildRock(boulder(xy, radius, height, seabedHeight(seabed, xy.x(), xy.y()), seed, scale)));
  }
  return finishWorld(draft, options, scale);
}

}  // namespace auv::sim::worldgen
