#pragma once
// The reconstruction stages, listed once (stages.cc). `auv recon <stage>` (tools/), `auv recon
// run` (pipeline.h) and the sections a recon.yaml may hold all come from this list.

#include <string>
#include <vector>

#include "auv/recon/common/stage.h"

namespace auv::recon::pipeline {

/// Every stage in the order of `auv recon --help`: calibrate, then the chain in the paper's
/// order (section 3: keyframes -> correct -> features -> match -> sfm -> dense -> mesh ->
/// texture), then evaluate and figures.
const std::vector<const Stage*>& stages();

/// The stages `auv recon run` chains (Stage::chained()), in order.
std::vector<const Stage*> chainedStages();

/// The stage named `name`; nullptr when there is none.
const Stage* findStage(const std::string& name);

}  // namespace auv::recon::pipeline
