#include "auv/recon/common/stage.h"

#include <stdexcept>

namespace auv::recon {

std::filesystem::path shardFolder(const Survey& survey, const std::string& stage, Shard shard) {
  return survey.root() / ".shards" / stage /
         (std::to_string(shard.index) + "-of-" + std::to_string(shard.count));
}

StageReport shardReport(const std::string& stage, Shard shard, const std::string& done) {
  StageReport report;
  report.summary =
      "shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count) + ": " + done;
  report.lines.push_back(stage + ": " + report.summary);
  return report;
}

StageReport mergedReport(StageReport whole, int count) {
  whole.summary += " (" + std::to_string(count) + " shards merged)";
  return whole;
}

void Shard::check() const {
  if (count < 1 || index < 0 || index >= count) {
    throw std::invalid_argument("shard " + std::to_string(index) + "/" + std::to_string(count) +
                                ": expected 0 <= index < count");
  }
}

StageReport Stage::runShard(const Survey&, const StageOptions&, Shard) const {
  throw std::logic_error(name() + ": this stage is not sharded");
}

StageReport Stage::mergeShards(const Survey&, const StageOptions&, int) const {
  throw std::logic_error(name() + ": this stage is not sharded");
}

}  // namespace auv::recon
