// `auv node list`, `auv interface list|show`, `auv run`.
#include <iostream>
#include <memory>

#include "auv/interfaces/component.h"
#include "auv/interfaces/graph.h"
#include "cli/cli_common.h"

namespace auv::bringup {

int nodeMain(const std::vector<std::string>& argv) {
  const Args args(argv, {"-a", "-v"}, {"--wait"});
  constexpr const char* kUsage = "usage: auv node list [-a] [-v] [--wait s]";
  if (args.helpRequested()) {
    std::cout << kUsage << "\n";
    return 0;
  }
  if (args.positional().empty() || args.positional()[0] != "list") throw CliError(kUsage);
  interfaces::GraphInspector inspector(interfaces::vendorFromEnvironment(),
                                       interfaces::domainFromEnvironment());
  const auto snapshot = inspector.waitFor(
      [](const interfaces::GraphSnapshot&) { return false; },
      std::chrono::milliseconds(static_cast<int64_t>(args.number("--wait", 2.0) * 1000)));
  for (const auto& p : snapshot.participants) {
    if (!p.is_auv && !args.flag("-a")) continue;  // -a: also participants of other programs
    std::cout << "/" << (p.node_name.empty() ? "_unnamed" : p.node_name);
    if (args.flag("-v"))
      std::cout << "  vendor=" << p.vendor << " host=" << p.host << " pid=" << p.pid
                << " guid=" << interfaces::toString(p.guid);
    std::cout << "\n";
  }
  return 0;
}

int interfaceMain(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {});
  constexpr const char* kUsage = "usage: auv interface list | auv interface show <type>";
  if (args.helpRequested()) {
    std::cout << kUsage << "\n";
    return 0;
  }
  const std::string command = args.positional().empty() ? "" : args.positional()[0];
  if (command == "list") {
    for (const auto& ts : msg::allTypes())
      std::cout << ts.name << (ts.keyed ? "  (keyed)" : "") << "\n";
    return 0;
  }
  if (command == "show") {
    const std::string name = args.at(1, "message type");
    const msg::TypeSupport* ts = msg::findType(name);
    if (ts == nullptr)
      throw CliError("unknown message type '" + name + "' (see `auv interface list`)");
    auto sample = ts->create_sample();
    YAML::Emitter out;
    out << ts->to_yaml(sample.get());
    std::cout << "# " << ts->name << " with default values (usable with `auv topic pub`)\n"
              << out.c_str() << "\n";
    return 0;
  }
  throw CliError(kUsage);
}

/// The component and node name of `component[:node_name]`.
interfaces::ComponentSpec parseSpec(const std::string& item) {
  const auto colon = item.find(':');
  return {item.substr(0, colon), colon == std::string::npos ? "" : item.substr(colon + 1)};
}

/// `auv run <component>... --help`: every declared parameter of each component with the values
/// `options` give it. The component is configured on a node of the domain, never activated: it
/// joins the domain for a moment and publishes nothing. A configuration that fails after its
/// declarations (the recorder without `root`) still prints them, then the error; the exit code
/// is the error's (config::exitCodeFor: 2 for bad input).
int describeComponents(const std::vector<std::string>& items,
                       const interfaces::NodeOptions& options) {
  auto& registry = interfaces::ComponentRegistry::instance();
  int status = 0;
  try {
    for (const std::string& item : items) {
      const interfaces::ComponentSpec spec = parseSpec(item);
      const interfaces::ComponentInfo* info = registry.find(spec.component);
      if (info == nullptr)
        throw CliError("unknown component '" + spec.component + "' (see `auv run --list`)");
      interfaces::Node node(spec.node_name.empty() ? spec.component : spec.node_name, options);
      std::unique_ptr<interfaces::Component> component = info->create();
      std::string error;
      try {
        component->configure(node);
      } catch (const std::exception& e) {  // as `auv run` reports a bad configuration
        error = e.what();
        status = config::exitCodeFor(e);
      }
      std::cout << "# " << spec.component << ": " << info->description << "\n"
                << node.parameters().describe() << "\n";
      if (!error.empty()) {
        std::cerr << "auv run: " << error << std::endl;
        continue;
      }
      component->cleanup();
    }
  } catch (const std::exception& e) {
    std::cerr << "auv run: " << e.what() << std::endl;
    return config::exitCodeFor(e);
  }
  return status;
}

int runMain(const std::vector<std::string>& argv) {
  const Args args(argv, {"--list"}, {"--params", "-p"});
  // Options may repeat: collect them in order from the raw arguments.
  interfaces::NodeOptions options;
  for (size_t i = 0; i + 1 < argv.size(); ++i) {
    if (argv[i] == "--params") options.params_files.push_back(argv[i + 1]);
    if (argv[i] == "-p") options.overrides.push_back(argv[i + 1]);
  }
  auto& registry = interfaces::ComponentRegistry::instance();
  registry.loadPlugins();
  if (args.flag("--list") || args.positional().empty()) {
    for (const auto& info : registry.list())
      std::cout << info.name << "  " << info.description << "\n";
    if (args.positional().empty() && !args.flag("--list"))
      std::cerr << "usage: auv run <component>[:<node_name>] ... [--params f.yaml]... "
                   "[-p name:=value]...\n       auv run <component> --help   # its parameters\n";
    return args.flag("--list") || args.helpRequested() ? 0 : 2;
  }
  if (args.helpRequested()) return describeComponents(args.positional(), options);
  std::vector<interfaces::ComponentSpec> specs;
  for (const std::string& item : args.positional()) specs.push_back(parseSpec(item));
  return interfaces::runComponents(specs, options);
}

}  // namespace auv::bringup
