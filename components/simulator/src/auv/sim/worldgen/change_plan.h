#pragma once
// Seeded changes for a later visit of a generated world (`auv sim generate <world> --epoch 2`):
// a fallen block, a removed and a moved boulder (when loose rocks lie there), a patch of growth,
// a scoured patch and a bleached patch, placed where the cameras film the first query: on the
// surfaces seen looking down (within 25 deg of straight down) from its route, inside a stated
// stretch of it.

#include <cstdint>
#include <string>
#include <vector>

#include "auv/sim/world/site_changes.h"
#include "auv/sim/worldgen/world_generator.h"

namespace auv::sim {

struct ChangePlanOptions {
  uint64_t seed = 1;         ///< same world and seed, same changes
  double along_from = 0.25;  ///< the stretch of the first query's route (fractions of its length)
  double along_to = 0.5;     ///< the changes are placed under; the default is the canyon's
                             ///< first traverse that the main job films (55-135 s)
  /// Throws ConfigError naming the field.
  void check() const;
};

/// The changes (world NED). Fewer than six when the stretch offers no loose rock (no remove or
/// move) or no room; throws ConfigError when nothing at all could be placed.
std::vector<SiteChange> planSiteChanges(const GeneratedWorld& world,
                                        const ChangePlanOptions& options);

/// The scenario's `changes:` section for `changes`, as YAML text.
std::string siteChangesYaml(const std::vector<SiteChange>& changes);

/// Writes <dir>/<name>_epoch2.yaml: the scenario `scenario_yaml` (the earlier visit's, next to
/// the same mesh) with `changes:` and name <name>_epoch2. Returns its path.
std::string writeEpochScenario(const GeneratedWorld& world, const std::vector<SiteChange>& changes,
                               const std::string& dir, int epoch);

}  // namespace auv::sim
