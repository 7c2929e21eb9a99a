#pragma once
// `nav/odometry` -> what the controller acts on (frames and units per idl/README.md).

#include "auv/control/controller.h"
#include "auv/msg/all.h"

namespace auv::control {

/// What the controller acts on, from `nav/odometry`. The velocity counts as measured with
/// DVL_VALID or GROUND_TRUTH among the source flags, or no flags at all (a source that does not
/// fill them is trusted). The yaw is that of the orientation whatever the small roll and pitch;
/// `orientation_ok` is false for a quaternion far from unit norm (an unset orientation).
ControllerNavigation toControllerNavigation(const msg::Odometry& odometry, bool& orientation_ok);

}  // namespace auv::control
