#include "auv/sim/camera/camera_rig.h"

#include <set>
#include <stdexcept>

namespace auv::sim {

CameraRig CameraRig::defaults() {
  CameraRig rig;
  for (const char* id : {"left", "right", "forward"}) {
    rig.cameras.push_back(CameraOptions::defaults(id));
  }
  return rig;
}

CameraRig CameraRig::fromYaml(const YamlSection& root) {
  if (!root.has("cameras")) return defaults();
  CameraRig rig;
  for (const YamlSection& element : root.childList("cameras")) {
    rig.cameras.push_back(CameraOptions::fromYaml(element));
  }
  if (rig.cameras.empty()) root.fail("cameras", "the list is empty; remove it for the default rig");
  try {
    rig.check();
  } catch (const ConfigError& e) {
    throw ConfigError(root.file() + ": " + e.what());
  }
  return rig;
}

void CameraRig::check() const {
  if (cameras.empty()) throw ConfigError("cameras: no camera");
  std::set<std::string> seen;
  for (const CameraOptions& camera : cameras) {
    camera.check();
    if (!seen.insert(camera.id).second) {
      throw ConfigError("cameras[" + camera.id + "].id: used by two cameras");
    }
  }
}

std::vector<std::string> CameraRig::ids() const {
  std::vector<std::string> out;
  for (const CameraOptions& camera : cameras) out.push_back(camera.id);
  return out;
}

const CameraOptions& CameraRig::camera(const std::string& id) const {
  for (const CameraOptions& camera : cameras) {
    if (camera.id == id) return camera;
  }
  std::string known;
  for (const CameraOptions& camera : cameras) known += (known.empty() ? "" : ", ") + camera.id;
  throw std::invalid_argument("no camera '" + id + "' (cameras: " + known + ")");
}

std::vector<SpotLight> CameraRig::lightsInWorld(const Eigen::Isometry3d& body_to_world) const {
  std::vector<SpotLight> lights;
  for (const CameraOptions& camera : cameras) {
    if (!camera.lights || camera.light_intensity <= 0) continue;
    const Eigen::Isometry3d camera_to_world = body_to_world * camera.cameraToBody();
    SpotLight light;
    light.position = camera_to_world.translation().cast<float>();
    light.direction = camera_to_world.linear().col(2).cast<float>();
    light.intensity = static_cast<float>(camera.light_intensity);
    light.beam_deg = static_cast<float>(camera.light_beam_deg);
    lights.push_back(light);
  }
  return lights;
}

}  // namespace auv::sim
