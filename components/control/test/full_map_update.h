#pragma once
// `tree` as the mapping component's FULL map update `sequence` (OctoMap binary), for the tests.

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

#include "auv/msg/all.h"

namespace auv::control::test {

inline msg::OctomapUpdate fullMapUpdate(const octomap::OcTree& tree, uint64_t sequence) {
  std::ostringstream stream;
  tree.writeBinaryConst(stream);
  const std::string data = stream.str();
  msg::OctomapUpdate update;
  update.header().frame_id("world");
  update.map_id("octomap");
  update.sequence_number(sequence);
  update.kind(msg::OCTOMAP_UPDATE_FULL);
  update.encoding(msg::OCTOMAP_ENCODING_BINARY);
  update.tree_type(tree.getTreeType());
  update.resolution(tree.getResolution());
  update.data(std::vector<uint8_t>(data.begin(), data.end()));
  return update;
}

}  // namespace auv::control::test
