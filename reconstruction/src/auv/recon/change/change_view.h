#pragma once
// The 3-D view of a comparison: survey 2's mesh coloured by the change (mesh_change.ply),
// rendered from above and to the side (south-west, 45° down) with Lambert shading, so walls,
// overhangs and the floor show their change in one picture (the top-down map flattens walls).
#include <filesystem>

#include <open3d/geometry/TriangleMesh.h>

namespace auv::recon::change {

struct ChangeViewOptions {
  int width = 1600, height = 1200;  ///< px
  double azimuth_deg = 225.0;       ///< the camera's bearing from the mesh's centre (NED: 0 north)
  double elevation_deg = 45.0;      ///< above the horizontal
  double fov_deg = 50.0;            ///< horizontal field of view
};

/// Writes the PNG (through a temporary name). `mesh` has vertex colours; NED frame (z down).
/// Throws std::runtime_error when the file cannot be written.
void writeChangeView(const std::filesystem::path& file, const open3d::geometry::TriangleMesh& mesh,
                     const ChangeViewOptions& options = {});

}  // namespace auv::recon::change
