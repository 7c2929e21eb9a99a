#pragma once
// Components: the unit of deployment, like rclcpp components with Nav2's two-phase life.
// A component is a class registered by name; `auv run <name>` loads it alone or together
// with others in one process (composition), each with its own Node.
//
//   class Talker : public auv::interfaces::Component {
//     void configure(Node& node) override;   // read + validate parameters, create entities
//     void activate() override;              // start timers / work
//   };
//   AUV_REGISTER_COMPONENT(Talker, "demo_talker", "publishes a counter on /chatter")

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "auv/interfaces/node.h"

namespace auv::interfaces {

class Component {
 public:
  virtual ~Component() = default;
  /// Reads and validates parameters and creates publishers, subscriptions and timers.
  /// Throws (ParameterError, std::invalid_argument, ...) with a message naming the problem;
  /// the host reports it and exits non-zero without activating anything.
  virtual void configure(Node& node) = 0;
  /// Starts work (e.g. enables timers). Called once after every component configured.
  virtual void activate() {}
  /// Stops work; the node's entities stay until cleanup.
  virtual void deactivate() {}
  /// Releases what configure created.
  virtual void cleanup() {}
};

struct ComponentInfo {
  std::string name;         ///< Registered name, used by `auv run <name>`.
  std::string description;  ///< One line for `auv run --list`.
  std::function<std::unique_ptr<Component>()> create;
};

/// Where component libraries are looked for, in order: AUV_COMPONENT_PATH; the
/// `lib/auv_components` folder of `executable`'s prefix (<prefix>/bin/<executable>) and, in an
/// isolated colcon install (.colcon_install_layout says so), of the other packages' prefixes
/// beside it; `lib/auv_components` under each CMAKE_PREFIX_PATH entry. No executable: the
/// environment's folders only.
std::vector<std::filesystem::path> componentSearchPath(const std::filesystem::path& executable);

/// Process-wide registry filled by AUV_REGISTER_COMPONENT at library load time.
class ComponentRegistry {
 public:
  static ComponentRegistry& instance();
  void add(ComponentInfo info);
  const ComponentInfo* find(const std::string& name) const;
  std::vector<ComponentInfo> list() const;
  /// Loads every component library (lib*_components.so) in the folders of
  /// componentSearchPath() for the running executable; returns the files loaded. Errors name
  /// the library.
  std::vector<std::string> loadPlugins();

 private:
  std::map<std::string, ComponentInfo> components_;
};

namespace detail {
struct ComponentRegistrar {
  ComponentRegistrar(const char* name, const char* description,
                     std::function<std::unique_ptr<Component>()> create) {
    ComponentRegistry::instance().add({name, description, std::move(create)});
  }
};
}  // namespace detail

#define AUV_REGISTER_COMPONENT_CAT2(a, b) a##b
#define AUV_REGISTER_COMPONENT_CAT(a, b) AUV_REGISTER_COMPONENT_CAT2(a, b)
/// Registers `Class` under `name` when its library is loaded.
#define AUV_REGISTER_COMPONENT(Class, name, description)                           \
  static ::auv::interfaces::detail::ComponentRegistrar AUV_REGISTER_COMPONENT_CAT( \
      auv_component_registrar_, __LINE__)(name, description,                       \
                                          [] { return std::make_unique<Class>(); });

/// One component instance to host: which component, under which node name.
struct ComponentSpec {
  std::string component;
  std::string node_name;  ///< Defaults to the component name.
};

/// Runs components in this process: creates a Node per component (with the given options),
/// configures all, activates all, spins one executor until SIGINT/SIGTERM, then deactivates
/// and cleans up. Returns the process exit code; errors are logged with the component name.
int runComponents(const std::vector<ComponentSpec>& specs, const NodeOptions& options);

}  // namespace auv::interfaces
