#pragma once
// A reader's copy of the mapping component's map, kept from `map/update`: FULL replaces it,
// unless it is the version the copy holds (same sequence number and stamp: the mapper sends a
// FULL as the version of the update before it); INCREMENTAL applies a diff when it continues
// the copy's version. A diff that does not
// continue it (a lost update) leaves the copy as it was and marks it stale until the next FULL
// arrives (the reader may ask for one with `map/request_full`).

#include <cstdint>
#include <memory>
#include <string>

#include <octomap/OcTree.h>

#include "auv/msg/all.h"

namespace auv::mapping {

class MapReplica {
 public:
  enum class Outcome {
    APPLIED,    ///< the copy is now at update.sequence_number
    UNCHANGED,  ///< a FULL map of the version the copy holds already: not read
    IGNORED,    ///< another map_id, or a kind/encoding this reader does not use
    GAP,        ///< an increment that does not continue the copy: needs a FULL map
    REJECTED,   ///< unreadable data or another resolution (see error()); the copy is unchanged
  };

  /// Follows the map `map_id` with leaves of `resolution` m.
  MapReplica(std::string map_id, double resolution);

  Outcome apply(const msg::OctomapUpdate& update);

  /// The copy (an empty tree of the resolution before the first FULL map).
  const octomap::OcTree& tree() const { return *tree_; }
  /// The same, for readers that need a mutable tree (DynamicEDT3D takes one); it is replaced,
  /// not updated, by a FULL map.
  octomap::OcTree& tree() { return *tree_; }
  /// Version held (0: none yet).
  uint64_t sequence() const { return sequence_; }
  /// True after a GAP or REJECTED until a FULL map is applied.
  bool needsFullMap() const { return needs_full_; }
  /// Why the last update was REJECTED.
  const std::string& error() const { return error_; }

 private:
  std::string map_id_;
  double resolution_;
  std::unique_ptr<octomap::OcTree> tree_;
  uint64_t sequence_ = 0;
  int64_t stamp_ns_ = 0;  // of the update that made the version held
  bool needs_full_ = false;
  std::string error_;
};

/// Reads a FULL update's data (either encoding) into a new OcTree; throws std::runtime_error.
std::unique_ptr<octomap::OcTree> readFullMap(const msg::OctomapUpdate& update);

}  // namespace auv::mapping
