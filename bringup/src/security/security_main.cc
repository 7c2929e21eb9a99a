// `auv security`: creates and lists DDS Security keystores (docs/security.md).
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "security/keystore.h"

namespace {

constexpr const char* kUsage =
    "usage: auv security init <keystore> [--identities vehicle,shore] [--domain N]\n"
    "                         [--days 3650] [--organization auv-inspect] [--force]\n"
    "       auv security add <keystore> <identity> [--force]\n"
    "       auv security list <keystore>\n"
    "       auv security check <keystore> --cyclonedds <ids> --fastdds <ids>\n"
    "  init  creates a project CA (prime256v1), a key + certificate per identity, the\n"
    "        governance (authentication, access control, encryption of every topic and of\n"
    "        discovery) and one permissions document per identity, signed by the CA.\n"
    "        Refuses to replace an existing keystore unless --force.\n"
    "  add   adds one identity signed by the keystore's CA.\n"
    "  list  identities with subject, expiry and whether their files verify.\n"
    "  check whether processes with these identities can authenticate across the two DDS\n"
    "        vendors (exit 0) or not (exit 1, with names that would work).\n"
    "Run a process secured with AUV_SECURITY_KEYSTORE=<keystore> AUV_SECURITY_IDENTITY=<name>\n"
    "(AUV_SECURITY_STRATEGY=Enforce|Permissive). Same-vendor pairs only: see docs/security.md.\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = text.find(',', start);
    items.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return items;
}

int parseInt(const std::string& option, const std::string& value) {
  char* end = nullptr;
  const long number = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || number < -1000000 || number > 1000000)
    throw UsageError(option + ": expected an integer, got '" + value + "'");
  return static_cast<int>(number);
}

// Positional arguments and options of one subcommand; options take one value except --force.
struct Arguments {
  std::vector<std::string> positional;
  auv::bringup::KeystoreOptions options;
};

Arguments parse(const std::vector<std::string>& args, bool allow_init_options) {
  Arguments parsed;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--force") {
      parsed.options.force = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) {
      parsed.positional.push_back(arg);
      continue;
    }
    if (!allow_init_options) throw UsageError("unknown option " + arg);
    if (i + 1 >= args.size()) throw UsageError(arg + ": needs a value");
    const std::string& value = args[++i];
    if (arg == "--identities") {
      parsed.options.identities = splitList(value);
    } else if (arg == "--domain") {
      parsed.options.domain_id = parseInt(arg, value);
      if (parsed.options.domain_id < 0)
        throw UsageError("--domain: expected a DDS domain id in [0, 230], got " + value);
    } else if (arg == "--days") {
      parsed.options.valid_days = parseInt(arg, value);
    } else if (arg == "--organization") {
      parsed.options.organization = value;
    } else {
      throw UsageError("unknown option " + arg);
    }
  }
  return parsed;
}

int initCommand(const std::vector<std::string>& args) {
  Arguments parsed = parse(args, true);
  if (parsed.positional.size() != 1) throw UsageError("init: give exactly one keystore folder");
  const std::string problem = parsed.options.check();
  if (!problem.empty()) throw UsageError("--" + problem);
  auv::bringup::createKeystore(parsed.positional[0], parsed.options);
  std::cout << "security: keystore " << parsed.positional[0] << " with identities";
  for (const std::string& name : parsed.options.identities) std::cout << " " << name;
  std::cout << " (domain "
            << (parsed.options.domain_id < 0 ? std::string("0-230")
                                             : std::to_string(parsed.options.domain_id))
            << ", valid " << parsed.options.valid_days << " days)\n"
            << "keep " << parsed.positional[0]
            << "/private/ca.key.pem off the vehicle; give each host only its identity\n";
  return 0;
}

int addCommand(const std::vector<std::string>& args) {
  Arguments parsed = parse(args, false);
  if (parsed.positional.size() != 2) throw UsageError("add: give a keystore and an identity");
  auv::bringup::addIdentity(parsed.positional[0], parsed.positional[1], parsed.options);
  std::cout << "security: added identity " << parsed.positional[1] << "\n";
  return 0;
}

int listCommand(const std::vector<std::string>& args) {
  Arguments parsed = parse(args, false);
  if (parsed.positional.size() != 1) throw UsageError("list: give exactly one keystore folder");
  std::string ca_expiry;
  const auto identities = auv::bringup::listKeystore(parsed.positional[0], &ca_expiry);
  std::cout << "CA expires " << ca_expiry << "\n";
  bool all_valid = true;
  for (const auto& identity : identities) {
    std::cout << identity.name << "\t" << identity.subject << "\texpires "
              << identity.certificate_expiry << "\t"
              << (identity.problem.empty() ? "ok" : "INVALID: " + identity.problem) << "\n";
    all_valid = all_valid && identity.problem.empty();
  }
  return all_valid ? 0 : 1;
}

}  // namespace

int checkCommand(const std::vector<std::string>& args) {
  std::vector<std::string> folders, cyclonedds, fastdds;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--cyclonedds" || args[i] == "--fastdds") {
      if (i + 1 >= args.size()) throw UsageError(args[i] + ": needs a value");
      std::vector<std::string>& ids = args[i] == "--cyclonedds" ? cyclonedds : fastdds;
      ids = splitList(args[++i]);
    } else if (args[i].rfind("--", 0) == 0) {
      throw UsageError("unknown option " + args[i]);
    } else {
      folders.push_back(args[i]);
    }
  }
  if (folders.size() != 1) throw UsageError("check: give exactly one keystore folder");
  if (cyclonedds.empty() || fastdds.empty())
    throw UsageError("check: give the identities of both vendors (--cyclonedds, --fastdds)");
  const std::string problem = auv::bringup::crossVendorProblem(
      auv::bringup::keystoreOrganization(folders[0]), cyclonedds, fastdds);
  if (problem.empty()) {
    std::cout << "security: every Cyclone DDS identity starts the handshake with every Fast DDS "
                 "identity: supported\n";
    return 0;
  }
  std::cout << problem;
  return 1;
}

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  try {
    if (args[0] == "init") return initCommand(rest);
    if (args[0] == "add") return addCommand(rest);
    if (args[0] == "list") return listCommand(rest);
    if (args[0] == "check") return checkCommand(rest);
    throw UsageError("unknown command '" + args[0] + "'");
  } catch (const UsageError& e) {
    std::cerr << "auv security: " << e.what() << "\n" << kUsage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "auv security: " << e.what() << "\n";
    return 1;
  }
}
