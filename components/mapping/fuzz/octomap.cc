// Fuzz harness: OctoMap streams as the vehicle reads them from outside: `.ot` checkpoints and
// the map/update data of other mappers (ot_stream::readTree, MapBuilder::applyDiff) and `.bt`
// files given as initial_map and BINARY map/updates (ot_stream::readBinaryTree). A clear error is a
// std::runtime_error; anything else (a crash, a sanitizer report, another exception) is a bug.
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/mapping/map_builder.h"
#include "auv/mapping/ot_stream.h"

using auv::mapping::MapBuilder;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  try {
    std::istringstream stream(input);
    auv::mapping::ot_stream::readTree(stream);
  } catch (const std::runtime_error&) {
  }
  try {
    octomap::OcTree replica(0.5);
    MapBuilder::applyDiff(input, replica);
  } catch (const std::runtime_error&) {
  }
  try {
    std::istringstream stream(input);
    octomap::OcTree tree(0.5);
    auv::mapping::ot_stream::readBinaryTree(stream, tree);
  } catch (const std::runtime_error&) {
  }
  return 0;
}

/// A small map of a wall seen from two places, in each format the vehicle reads.
std::vector<std::string> auvFuzzSeeds() {
  MapBuilder builder(MapBuilder::Options{});
  builder.enableChangeTracking(true);
  for (int i = -10; i <= 10; ++i) {
    auv::mapping::BeamGeometry beam;
    beam.direction = Eigen::Vector3d(1.0, 0.05 * i, 0.0).normalized();
    beam.return_range = 6.0;
    builder.insertBeam(beam, Eigen::Isometry3d::Identity());
  }
  const std::string diff = builder.takeDiff().data;
  return {builder.fullWithProbabilities(), builder.fullBinary(), diff};
}
