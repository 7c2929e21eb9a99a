#include "auv/mapping/map_replica.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "auv/interfaces/msg_time.h"
#include "auv/mapping/map_builder.h"
#include "auv/mapping/ot_stream.h"

namespace auv::mapping {

std::unique_ptr<octomap::OcTree> readFullMap(const msg::OctomapUpdate& update) {
  std::istringstream stream(std::string(update.data().begin(), update.data().end()));
  if (update.encoding() == msg::OCTOMAP_ENCODING_BINARY) {
    auto tree = std::make_unique<octomap::OcTree>(update.resolution());
    ot_stream::readBinaryTree(stream, *tree);
    return tree;
  }
  return ot_stream::readTree(stream);
}

MapReplica::MapReplica(std::string map_id, double resolution)
    : map_id_(std::move(map_id)),
      resolution_(resolution),
      tree_(std::make_unique<octomap::OcTree>(resolution)) {}

MapReplica::Outcome MapReplica::apply(const msg::OctomapUpdate& update) {
  if (update.map_id() != map_id_) return Outcome::IGNORED;
  if (std::abs(update.resolution() - resolution_) > 1e-9) {
    error_ = "resolution " + std::to_string(update.resolution()) + " m, expected " +
             std::to_string(resolution_) + " m";
    return Outcome::REJECTED;
  }
  try {
    const int64_t stamp_ns = interfaces::toNanoseconds(update.header().stamp());
    if (update.kind() == msg::OCTOMAP_UPDATE_FULL) {
      // The stamp tells a restarted mapper's version of the same number from ours.
      if (!needs_full_ && sequence_ != 0 && update.sequence_number() == sequence_ &&
          stamp_ns == stamp_ns_) {
        return Outcome::UNCHANGED;
      }
      tree_ = readFullMap(update);
      sequence_ = update.sequence_number();
      stamp_ns_ = stamp_ns;
      needs_full_ = false;
      return Outcome::APPLIED;
    }
    if (update.kind() != msg::OCTOMAP_UPDATE_INCREMENTAL ||
        update.encoding() != msg::OCTOMAP_ENCODING_FULL) {
      return Outcome::IGNORED;
    }
    if (sequence_ == 0 || update.base_sequence() != sequence_) {
      needs_full_ = true;  // a gap in the chain: only a FULL map repairs the copy
      return Outcome::GAP;
    }
    MapBuilder::applyDiff(std::string(update.data().begin(), update.data().end()), *tree_);
    sequence_ = update.sequence_number();
    stamp_ns_ = stamp_ns;
    return Outcome::APPLIED;
  } catch (const std::exception& error) {
    needs_full_ = true;
    error_ = error.what();
    return Outcome::REJECTED;
  }
}

}  // namespace auv::mapping
