#pragma once
// Tiny survey and run folders in the real formats (README.md, "Tests"), and the benchmark's
// large textured terrain.

#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace auv::view::test {

struct SurveyCounts {
  size_t triangles, dense_points, sparse_points, cameras;
};
/// textured/model.obj + .mtl + two PNG pages, dense/fused.ply, sparse/ (COLMAP text),
/// figures/cameras.ply, report.json, evaluation.json (an alignment), simulation.json -> a
/// ground-truth run with navigation.tum and trajectory.tum, recordings/<camera>/*.frames.csv.
SurveyCounts writeDemoSurvey(const std::filesystem::path& survey);

struct RunCounts {
  size_t voxels, tree_edges, paths, waypoints, collisions;
};
/// mission/map.bt (OctoMap), tree_1.csv, tree_2.csv, paths.csv, waypoints.csv, events.csv;
/// ground_truth/trajectory.tum, navigation.tum, collisions.csv.
RunCounts writeDemoRun(const std::filesystem::path& run);

/// textured/model.obj of a rolling terrain of about `triangles` triangles on `pages` 2048²
/// atlas pages (the benchmark's stand-in for the demo's model); with `patch_per_face` every
/// face has texture coordinates of its own, as `auv recon texture` writes them.
void writeTerrainSurvey(const std::filesystem::path& survey, size_t triangles, int pages = 1,
                        bool patch_per_face = false);

/// The fixture atlas's colour at pixel (x, y) of a `size`² page (y down, as stored).
void texel(int x, int y, int size, uint8_t rgb[3]);

}  // namespace auv::view::test
