#include "auv/recon/common/stage.h"

#include <stdexcept>

namespace auv::recon {

std::filesystem::path shardFolder(const Survey& survey, const std::string& stage, Shard shard) {
  return survey.root() / ".shards" / stage /
         (std::to_string(shard.index) + "-of-" + std::to_string(shard.count));
}

StageReport Stage::runShard(const Survey&, const StageOptions&, Shard) const {
  throw std::logic_error(name() + ": this stage is not sharded");
}

StageReport Stage::mergeShards(const Survey&, const StageOptions&, int) const {
  throw std::logic_error(name() + ": this stage is not sharded");
}

}  // namespace auv::recon
