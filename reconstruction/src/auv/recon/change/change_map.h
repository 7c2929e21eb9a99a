#pragma once
// The top-down change map of a comparison (change/change_map.png): each core point's cell seen
// from above (north up, east right, NED), red where the surface came nearer its normal's side
// (gained), blue where it went away (lost), full colour where significant, pale where not,
// dark grey where not measured; where several core points share a cell (walls, overhangs) the
// largest change is shown. A legend states the colour scale.
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/change/m3c2.h"

namespace auv::recon::change {

/// The colour (RGB in [0, 1]) of a change of `distance` m at full colour `scale_m`: white at 0
/// to red (gained) or blue (lost), a quarter of the colour when not significant, dark grey when
/// not measured. The map and the coloured mesh share it.
Eigen::Vector3d changeColour(const M3C2Point& point, double scale_m);

/// Writes the map as PNG through a temporary name; `cell_m` is the core spacing, `scale_m` the
/// distance shown at full colour (larger ones saturate). Throws std::runtime_error when it
/// cannot write.
void writeChangeMap(const std::filesystem::path& file,
                    const std::vector<Eigen::Vector3d>& core_points,
                    const std::vector<M3C2Point>& comparison, double cell_m, double scale_m);

}  // namespace auv::recon::change
