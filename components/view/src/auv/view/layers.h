#pragma once
// Layers both views share.

#include <string>
#include <vector>

#include "auv/view/scene.h"
#include "auv/view/tables.h"

namespace auv::view {

/// A trajectory as one polyline, thinned to at most `max_points` vertices (a long mission at the
/// simulator's rate has 10^5 poses; the page needs the shape).
void addTrajectory(Scene& scene, const std::string& id, const std::string& label,
                   const std::vector<StampedPosition>& poses, const std::string& colour,
                   size_t max_points = 20000);

}  // namespace auv::view
