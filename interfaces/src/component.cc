#include "auv/interfaces/component.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "auv/config/errors.h"
#include "auv/interfaces/executor.h"

namespace auv::interfaces {
namespace fs = std::filesystem;

ComponentRegistry& ComponentRegistry::instance() {
  static ComponentRegistry registry;
  return registry;
}

void ComponentRegistry::add(ComponentInfo info) {
  const std::string name = info.name;
  components_[name] = std::move(info);
}

const ComponentInfo* ComponentRegistry::find(const std::string& name) const {
  auto it = components_.find(name);
  return it == components_.end() ? nullptr : &it->second;
}

std::vector<ComponentInfo> ComponentRegistry::list() const {
  std::vector<ComponentInfo> out;
  for (const auto& [name, info] : components_) out.push_back(info);
  return out;
}

std::vector<fs::path> componentSearchPath(const fs::path& executable) {
  std::vector<fs::path> dirs;
  auto split = [&dirs](const char* value, const char* suffix) {
    if (value == nullptr) return;
    std::stringstream in(value);
    std::string item;
    while (std::getline(in, item, ':')) {
      if (!item.empty()) dirs.push_back(*suffix ? fs::path(item) / suffix : fs::path(item));
    }
  };
  split(std::getenv("AUV_COMPONENT_PATH"), "");
  if (!executable.empty()) {
    // Merged colcon install: <prefix>/bin/auv next to <prefix>/lib/auv_components.
    const fs::path prefix = executable.parent_path().parent_path();
    dirs.push_back(prefix / "lib" / "auv_components");
    // Isolated colcon install: install/auv_bringup/bin/auv, install/<package>/lib/...: the
    // other packages' prefixes. Only there: the folder beside a merged install may hold other
    // installs (an older build, another branch) whose libraries would replace ours.
    std::ifstream layout(prefix.parent_path() / ".colcon_install_layout");
    std::string kind;
    std::error_code ec;
    if (layout >> kind && kind == "isolated") {
      for (const auto& sibling : fs::directory_iterator(prefix.parent_path(), ec))
        dirs.push_back(sibling.path() / "lib" / "auv_components");
    }
  }
  split(std::getenv("CMAKE_PREFIX_PATH"), "lib/auv_components");
  return dirs;
}

std::vector<std::string> ComponentRegistry::loadPlugins() {
  std::vector<std::string> loaded;
  std::set<fs::path> seen;
  std::error_code exe_error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", exe_error);
  for (const fs::path& dir : componentSearchPath(exe_error ? fs::path() : exe)) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const fs::path file = fs::weakly_canonical(entry.path(), ec);
      const std::string name = file.filename().string();
      if (file.extension() != ".so" || name.find("_components") == std::string::npos) continue;
      if (!seen.insert(file).second) continue;
      if (dlopen(file.c_str(), RTLD_NOW | RTLD_GLOBAL) == nullptr)
        throw std::runtime_error("cannot load component library " + file.string() + ": " +
                                 dlerror());
      loaded.push_back(file.string());
    }
  }
  return loaded;
}

int runComponents(const std::vector<ComponentSpec>& specs, const NodeOptions& options) {
  struct Instance {
    ComponentSpec spec;
    std::unique_ptr<Node> node;
    std::unique_ptr<Component> component;
  };
  std::vector<Instance> instances;
  Executor::installSignalHandlers();
  Executor executor;
  try {
    for (const ComponentSpec& spec : specs) {
      const ComponentInfo* info = ComponentRegistry::instance().find(spec.component);
      if (info == nullptr) {
        std::string known;
        for (const auto& c : ComponentRegistry::instance().list())
          known += (known.empty() ? "" : ", ") + c.name;
        throw std::invalid_argument("unknown component '" + spec.component +
                                    "' (known: " + (known.empty() ? "none found" : known) + ")");
      }
      Instance instance{spec, nullptr, info->create()};
      const std::string node_name = spec.node_name.empty() ? spec.component : spec.node_name;
      instance.node = std::make_unique<Node>(node_name, options);
      instance.component->configure(*instance.node);
      for (const std::string& unused : instance.node->parameters().unusedOverrides())
        instance.node->logger().warn("unused parameter " + unused);
      executor.add(*instance.node);
      instances.push_back(std::move(instance));
    }
    for (auto& instance : instances) instance.component->activate();
  } catch (const std::exception& e) {
    std::cerr << "auv run: " << e.what() << std::endl;
    for (auto& instance : instances) instance.component->cleanup();
    return config::exitCodeFor(e);  // a bad parameter is the user's input: 2
  }
  executor.spin();
  int status = 0;
  for (auto it = instances.rbegin(); it != instances.rend(); ++it) {
    try {
      it->component->deactivate();
      it->component->cleanup();
    } catch (const std::exception& e) {
      it->node->logger().error(std::string("shutdown failed: ") + e.what());
      status = 1;
    }
    executor.remove(*it->node);
  }
  return status;
}

}  // namespace auv::interfaces
