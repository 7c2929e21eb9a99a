#include "auv/recon/pipeline/stages.h"

#include <memory>

#include "auv/recon/calibration/calibrate_stage.h"
#include "auv/recon/change/compare_stage.h"
#include "auv/recon/color/correct_stage.h"
#include "auv/recon/color/restore_stage.h"
#include "auv/recon/dense/dense_stage.h"
#include "auv/recon/evaluate/evaluate_stage.h"
#include "auv/recon/evaluate/figures_stage.h"
#include "auv/recon/features/features_stage.h"
#include "auv/recon/features/match_stage.h"
#include "auv/recon/import/import_stage.h"
#include "auv/recon/keyframes/keyframes_stage.h"
#include "auv/recon/mesh/mesh_stage.h"
#include "auv/recon/overlay/masks_stage.h"
#include "auv/recon/sfm/sfm_stage.h"
#include "auv/recon/texture/texture_stage.h"

namespace auv::recon::pipeline {

namespace {

template <class... Each>
std::vector<std::unique_ptr<const Stage>> make() {
  std::vector<std::unique_ptr<const Stage>> list;
  (list.push_back(std::make_unique<const Each>()), ...);
  return list;
}

}  // namespace

const std::vector<const Stage*>& stages() {
  // The one list of stages, in order. A new stage (pipeline/README.md) is one entry here.
  static const std::vector<std::unique_ptr<const Stage>> owned =
      make<import::ImportStage,          // not chained: footage from outside the survey
           calibration::CalibrateStage,  // not chained: a chessboard recording
           overlay::MasksStage,          // not chained: masks are for the user to inspect
           keyframes::KeyframesStage,    // the chain of `auv recon run`, docs/paper.md §3.1-3.7
           color::CorrectStage, features::FeaturesStage, features::MatchStage, sfm::SfmStage,
           dense::DenseStage, mesh::MeshStage, color::RestoreStage, texture::TextureStage,
           evaluate::EvaluateStage,  // not chained: the simulated run (docs/paper.md §4.3)
           evaluate::FiguresStage,
           change::CompareStage>();  // not chained: two surveys
  static const std::vector<const Stage*> all = [] {
    std::vector<const Stage*> pointers;
    for (const auto& stage : owned) pointers.push_back(stage.get());
    return pointers;
  }();
  return all;
}

std::vector<const Stage*> chainedStages() {
  std::vector<const Stage*> chained;
  for (const Stage* stage : stages()) {
    if (stage->chained()) chained.push_back(stage);
  }
  return chained;
}

const Stage* findStage(const std::string& name) {
  for (const Stage* stage : stages()) {
    if (stage->name() == name) return stage;
  }
  return nullptr;
}

}  // namespace auv::recon::pipeline
