// `auv sim check <scenario.yaml|mesh>`: is this world usable? Prints a summary or the first
// problem, naming the file and field.
#include <filesystem>
#include <iostream>

#include "auv/config/errors.h"
#include "auv/sim/raycast/ray_caster.h"
#include "auv/sim/sensors/dvl_beams.h"
#include "auv/sim/sensors/multibeam.h"
#include "auv/sim/sensors/navigation.h"
#include "auv/sim/sensors/profiling_sonar.h"
#include "auv/sim/tools/commands.h"
#include "auv/sim/vehicle/vehicle.h"
#include "auv/sim/world/hull_contact.h"
#include "auv/sim/world/scenario.h"

namespace auv::sim {

int checkMain(const std::vector<std::string>& args) {
  if (args.size() != 1 || args[0] == "-h" || args[0] == "--help") {
    (args.size() == 1 ? std::cout : std::cerr)
        << "usage: auv sim check <scenario.yaml | mesh.ply | mesh.obj>\n"
           "Validates a scenario (its mesh, water, sensors, start and queries) or a bare mesh.\n";
    return args.size() == 1 ? 0 : 2;
  }
  const std::string path = args[0];
  try {
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".yaml" || ext == ".yml") {
      const Scenario scenario = loadScenario(path);
      MeshReport report;
      const Mesh mesh = loadWorldMesh(scenario, &report);
      const RayCaster world(mesh);
      std::cout << "scenario " << scenario.name << ": " << scenario.file << "\n"
                << "  mesh " << scenario.mesh_path << ": " << report.triangles << " triangles ("
                << report.removed_degenerate << " degenerate removed), "
                << (mesh.hasTexture() ? "textured " + std::to_string(mesh.texture.cols) + "x" +
                                            std::to_string(mesh.texture.rows)
                                      : std::string("vertex colours"))
                << "\n  bounds NED [" << report.bounds.min().transpose() << "] .. ["
                << report.bounds.max().transpose() << "] m\n"
                << "  water attenuation (1/m) R G B = " << scenario.water.attenuation.transpose()
                << "\n";
      for (const SiteChange& change : scenario.changes)
        std::cout << "  change " << change.name << ": " << toString(change.type) << " at ["
                  << change.center.transpose() << "]\n";
      // The vehicle: read as the simulator reads it (a misspelt key is an error here too) and
      // its hull, not a default one, checked against the world at the start.
      const VehicleModel vehicle = readVehicleModel(scenario.root.child("vehicle"));
      HullShape hull;
      hull.length = vehicle.length;
      hull.radius = vehicle.radius;
      Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
      start.translation() = scenario.start_position;
      start.linear() = Eigen::AngleAxisd(scenario.start_yaw, Eigen::Vector3d::UnitZ()).matrix();
      if (findHullContact(world, scenario.seabed_depth, hull, start)) {
        throw ConfigError(scenario.file +
                          ": vehicle.start: the vehicle would start inside the world");
      }
      // The sensor sections, read and checked as the simulator reads them.
      NavigationOptions::fromYaml(scenario.root.child("navigation"));
      SonarOptions::fromYaml(scenario.root.child("sonar"));
      const MultibeamOptions multibeam = MultibeamOptions::fromScenario(scenario.root);
      const DvlBeamsOptions dvl_beams = DvlBeamsOptions::fromScenario(scenario.root);
      std::cout << "  sensors: profiling sonar";
      if (multibeam.enabled) {
        std::cout << ", multibeam " << multibeam.beams << " x " << multibeam.rows << " beams over "
                  << multibeam.horizontal_aperture * 180.0 / M_PI << " deg at " << multibeam.rate
                  << " Hz";
      }
      if (dvl_beams.enabled) {
        std::cout << ", DVL beams at " << dvl_beams.beam_angle * 180.0 / M_PI << " deg";
      }
      std::cout << "\n";
      for (const MissionQuery& q : scenario.queries) {
        Eigen::Isometry3d goal = Eigen::Isometry3d::Identity();
        goal.translation() = q.goal;
        if (findHullContact(world, scenario.seabed_depth, hull, goal)) {
          throw ConfigError(scenario.file + ": queries: goal of '" + q.name +
                            "' lies inside the world");
        }
        std::cout << "  query " << q.name << ": goal [" << q.goal.transpose() << "] tolerance "
                  << q.tolerance << " m\n";
      }
      const MissionPlanning& m = scenario.mission;
      if (m.fixed_depth) {
        std::cout << "  mission: fixed depth (2-D, at the start depth)\n";
      } else {
        std::cout << "  mission: 3-D";
        if (m.hasBand())
          std::cout << ", depth band [" << m.min_depth << ", " << m.max_depth << "] m";
        std::cout << ", min altitude " << m.min_altitude << " m\n";
      }
      std::cout << "ok\n";
      return 0;
    }
    Mesh mesh = loadMesh(path);
    const MeshReport report = validateMesh(mesh);
    std::cout << "mesh " << path << ": " << report.triangles << " triangles ("
              << report.removed_degenerate << " degenerate removed), "
              << (mesh.hasTexture() ? "textured" : "vertex colours") << "\nok\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "auv sim check: " << e.what() << std::endl;
    return config::exitCodeFor(e);  // bad input 2, failures 1
  }
}

}  // namespace auv::sim
