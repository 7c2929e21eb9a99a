#pragma once
// The vehicle's cameras: the scenario's `cameras:` list, or the default rig of the paper's
// Sparus II (section 4.1): "left" and "right" looking down tilted 20 deg to port and
// starboard, "forward" looking ahead pitched 40 deg down.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "auv/sim/camera/camera_model.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

struct CameraRig {
  std::vector<CameraOptions> cameras;

  /// left, right, forward (CameraOptions::defaults of each).
  static CameraRig defaults();
  /// The `cameras:` list of a scenario file's root; absent -> defaults(). An empty list, a
  /// repeated id or a bad element throws ConfigError naming the file and field.
  static CameraRig fromYaml(const YamlSection& root);
  static CameraRig fromScenario(const Scenario& scenario) { return fromYaml(scenario.root); }

  /// Unique, valid cameras; throws ConfigError.
  void check() const;
  std::vector<std::string> ids() const;
  /// The camera with this id; throws std::invalid_argument listing the known ids.
  const CameraOptions& camera(const std::string& id) const;
  /// The artificial lights of the cameras that have them on, in the world frame, for the
  /// vehicle at `body_to_world`.
  std::vector<SpotLight> lightsInWorld(const Eigen::Isometry3d& body_to_world) const;
};

}  // namespace auv::sim
