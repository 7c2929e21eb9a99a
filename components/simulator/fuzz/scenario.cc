// Fuzz harness: scenario files as the simulator and `auv sim check` read them: loadScenario
// (world, water, vehicle start, queries, mission, `changes:`), then the sections each module
// reads itself (vehicle, navigation, sonar, multibeam, dvl_beams, cameras, lighting). The
// scenario is written to /tmp/auv_fuzz_scenario/scenario_<pid>.yaml for the call, beside empty
// mesh files (loadScenario checks that the mesh exists; the meshes are another harness's).
// A clear error is a ConfigError naming the file and the field; anything else (a crash, a
// sanitizer report, another exception) is a bug.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "auv/sim/camera/camera_rig.h"
#include "auv/sim/camera/image_formation.h"
#include "auv/sim/sensors/dvl_beams.h"
#include "auv/sim/sensors/multibeam.h"
#include "auv/sim/sensors/navigation.h"
#include "auv/sim/sensors/profiling_sonar.h"
#include "auv/sim/vehicle/vehicle.h"
#include "auv/sim/world/scenario.h"
#include "auv/sim/worldgen/change_plan.h"
#include "auv/sim/worldgen/world_generator.h"

namespace fs = std::filesystem;
using namespace auv::sim;

namespace {

/// The folder of the scenario files, with the (empty) meshes the seeds name.
const fs::path& folder() {
  static const fs::path path = [] {
    const fs::path dir = fs::temp_directory_path() / "auv_fuzz_scenario";
    fs::create_directories(dir);
    for (const char* mesh : {"world.obj", "reef.obj"}) {
      if (!fs::exists(dir / mesh)) std::ofstream(dir / mesh);
    }
    return dir;
  }();
  return path;
}

/// Runs one module's reader of its section; a ConfigError is its clear answer to bad input.
template <class Read>
void section(Read read) {
  try {
    read();
  } catch (const ConfigError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const fs::path file = folder() / ("scenario_" + std::to_string(getpid()) + ".yaml");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  Scenario scenario;
  try {
    scenario = loadScenario(file.string());
  } catch (const ConfigError&) {
  }
  std::error_code error;
  fs::remove(file, error);
  if (scenario.file.empty()) return 0;  // refused
  const YamlSection& root = scenario.root;
  section([&] { readVehicleModel(root.child("vehicle")); });
  section([&] { NavigationOptions::fromYaml(root.child("navigation")); });
  section([&] { SonarOptions::fromYaml(root.child("sonar")); });
  section([&] { MultibeamOptions::fromScenario(root); });
  section([&] { DvlBeamsOptions::fromScenario(root); });
  section([&] { CameraRig::fromScenario(scenario); });
  section([&] { IlluminationOptions::fromScenario(scenario); });
  return 0;
}

/// The scenario of every generated world (scenarioYaml, as `auv sim generate` writes it), one of
/// them with a change of every type (siteChangesYaml, as `--epoch 2` writes them), and the
/// scenario of components/simulator/README.md with every section.
std::vector<std::string> auvFuzzSeeds() {
  std::vector<std::string> seeds;
  WorldGenOptions options;
  options.detail = 0.02;  // the scenario text does not depend on the mesh's detail
  for (const std::string& name : availableWorlds()) {
    seeds.push_back(scenarioYaml(generateWorld(name, options), "world.obj"));
  }
  std::vector<SiteChange> changes;
  for (SiteChangeType type : {SiteChangeType::kAdd, SiteChangeType::kRemove, SiteChangeType::kMove,
                              SiteChangeType::kGrow, SiteChangeType::kAlbedo}) {
    SiteChange change;
    change.name = std::string("change_") + toString(type);
    change.type = type;
    change.center = {-6.0, 3.1, 7.9};
    change.translation = {1.5, 0.4, 0.05};
    change.yaw_deg = 15;
    changes.push_back(change);
  }
  seeds.push_back(seeds.front() + siteChangesYaml(changes));
  seeds.push_back(seeds.front() + siteChangesYaml({}));
  seeds.push_back(R"(name: my_reef
world:
  mesh: reef.obj
  up_axis: z
  origin: [0, 0, 0]
  yaw_deg: 0
  scale: 1.0
  default_color: [0.5, 0.5, 0.5]
  seabed_depth: 12
  surface_detail: {amplitude: 0.9, tile_size: 0.5, seed: 1}
water:
  attenuation: [0.8, 0.2, 0.25]
  backscatter: [0.65, 0.2, 0.22]
  veiling_light: [0.03, 0.22, 0.26]
vehicle:
  start: {position: [0, 0, 3], yaw_deg: 0}
navigation: {}
sonar: {}
multibeam:
  enabled: true
  position: [0.6, 0.0, 0.15]
  pitch_deg: 25
  yaw_deg: 0
  beams: 256
  rows: 4
  horizontal_aperture_deg: 120
  vertical_aperture_deg: 20
  rate: 10
  min_range: 0.5
  max_range: 30
  range_noise: 0.05
  max_incidence_deg: 85
  sound_speed: 1500
dvl_beams:
  enabled: true
  position: [0.0, 0.0, 0.2]
  beam_angle_deg: 30
  azimuth_offset_deg: 45
  rate: 5
  min_range: 0.3
  max_range: 60
  range_noise: 0.02
cameras:
  - {id: left, width: 640, height: 480, hfov_deg: 90, position: [0.5, -0.2, 0.1], pitch_deg: -30}
  - {id: forward, fx: 500, fy: 500, cx: 320, cy: 240, distortion: [0.1, -0.05, 0, 0]}
lighting: {}
queries:
  - {name: traverse, goal: [40, 5, 3], tolerance: 2.0}
mission:
  fixed_depth: false
  min_depth: 2
  max_depth: 10
  min_altitude: 1.5
changes: []
)");
  return seeds;
}
