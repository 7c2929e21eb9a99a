#pragma once
// A scenario: the world mesh and how it sits in the world frame, the water's optics, where the
// vehicle starts, the mission's start-to-goal queries and the sensor settings. One YAML file
// (format documented in components/simulator/README.md); relative paths are relative to it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/world/mesh.h"
#include "auv/sim/world/site_changes.h"
#include "auv/sim/world/surface_detail.h"

namespace auv::sim {

/// Per-channel (R, G, B) underwater image formation constants, after Akkaynak & Treibitz:
///   I = J * exp(-attenuation * d) + veiling_light * (1 - exp(-backscatter * d)).
struct WaterOptics {
  Eigen::Vector3d attenuation{0.37, 0.10, 0.12};    ///< 1/m, direct-signal attenuation per channel
  Eigen::Vector3d backscatter{0.30, 0.09, 0.10};    ///< 1/m, backscatter coefficient per channel
  Eigen::Vector3d veiling_light{0.03, 0.22, 0.26};  ///< linear RGB [0,1] of water seen at infinity
  double visibility = 0.0;  ///< m, when > 0 the coefficients above were derived from it

  /// Coastal water with the given visibility (m): the green attenuation is 3.912 / visibility
  /// (2 % contrast threshold, Koschmieder), red ~3.7x and blue ~1.2x green, so red is lost first.
  static WaterOptics fromVisibility(double visibility_m);
  /// Throws ConfigError (naming `where`) for non-finite or negative values.
  void check(const std::string& where) const;
};

/// A start-to-goal query of the mission (planner goal, NED).
struct MissionQuery {
  std::string name;
  Eigen::Vector3d goal{0, 0, 0};  ///< m NED
  double tolerance = 1.5;         ///< m
};

/// How the world's mission plans (the scenario's `mission:` section; written into the exported
/// mission file's `defaults`). fixed_depth: one horizontal plane at the start depth (the paper's
/// 2-D mode, for worlds of vertical walls); otherwise 3-D inside the depth band, keeping
/// min_altitude over known seabed (natural terrain: boulders, arches, overhangs).
struct MissionPlanning {
  bool fixed_depth = true;
  double min_depth = 0.0;     ///< m; min_depth = max_depth = 0: no band (bounds only)
  double max_depth = 0.0;     ///< m
  double min_altitude = 0.0;  ///< m above the seabed, 0 = none
  bool hasBand() const { return max_depth > min_depth; }
};

struct Scenario {
  std::string name;
  std::string description;
  std::string file;  ///< the YAML file, for messages

  // world:
  std::string mesh_path;            ///< absolute, resolved against the YAML's folder
  std::string up_axis = "z";        ///< the mesh's up axis: "z" or "y" (mapped to NED up, -z)
  Eigen::Vector3d origin{0, 0, 0};  ///< m NED, where the mesh origin lands
  double yaw_deg = 0.0;             ///< deg, rotation of the mesh about the vertical
  double scale = 1.0;               ///< uniform scale of the mesh's units to metres
  std::optional<Eigen::Vector3f> default_color;  ///< sRGB for meshes with no colour/texture
  double seabed_depth = 20.0;  ///< m, depth of the flat seabed beyond the mesh (altitude fallback)
  SurfaceDetailOptions surface_detail;  ///< fine albedo detail for cameras (off unless given)

  WaterOptics water;

  // vehicle start:
  Eigen::Vector3d start_position{0, 0, 0};  ///< m NED
  double start_yaw = 0.0;                   ///< rad, 0 = north

  std::vector<MissionQuery> queries;
  MissionPlanning mission;
  /// What changed at the site since an earlier visit (`changes:`), applied by loadWorldMesh.
  std::vector<SiteChange> changes;
  /// The scenario has a `changes:` section, even an empty one (`changes: []`, a later visit
  /// where nothing changed: a control); `auv sim render` then writes the change truth.
  bool later_visit = false;

  /// The whole file; modules read their own sections (`vehicle`, `navigation`, `sonar`,
  /// `multibeam`, `dvl_beams`, `cameras`, `simulation`) with their own options' fromYaml().
  YamlSection root{YAML::Node(), "", ""};

  /// Mesh coordinates -> world NED.
  Eigen::Affine3f meshToWorld() const;
};

/// Reads and checks a scenario file. Throws ConfigError naming the file and field.
Scenario loadScenario(const std::string& path);

/// Loads the scenario's mesh, moves it into the world frame, applies the default colour and
/// validates it, then applies the scenario's `changes:` (what each did into `applied`). Throws
/// ConfigError naming the mesh file, or the scenario file and the change that cannot apply.
Mesh loadWorldMesh(const Scenario& scenario, MeshReport* report = nullptr,
                   std::vector<AppliedChange>* applied = nullptr);

/// The world as it was before the scenario's `changes:` (the earlier visit).
Mesh loadWorldMeshBeforeChanges(const Scenario& scenario, MeshReport* report = nullptr);

}  // namespace auv::sim
