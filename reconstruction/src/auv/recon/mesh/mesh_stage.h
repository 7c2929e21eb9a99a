#pragma once
// `auv recon mesh`: <survey>/dense/fused.ply -> <survey>/mesh/mesh.ply (Poisson, trimmed) and
// mesh/mesh_untrimmed.ply (for inspection), report.json section "mesh" (README.md).

#include <filesystem>
#include <string>
#include <vector>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/stage.h"
#include "auv/recon/common/survey.h"
#include "auv/recon/mesh/surface.h"

namespace auv::recon::mesh {

struct MeshStageOptions {
  SurfaceOptions surface;
  bool write_untrimmed = true;  ///< also mesh/mesh_untrimmed.ply
  void check() const { surface.check(); }
  /// Binds every option to `--flag value` and to the `mesh:` section of a config file.
  void bind(OptionSet& set);
};

struct MeshStageResult {
  TrimStats stats;
  size_t cloud_points = 0;
  double area_untrimmed = 0, area = 0;  ///< m^2
  double seconds = 0;
};

/// The whole stage on a survey folder. The mesh folder is replaced only when everything is
/// written (StagedOutput): a failure leaves the previous mesh/ as it was.
MeshStageResult runMeshStage(const Survey& survey, const MeshStageOptions& options);

/// The `mesh` stage (common/stage.h): `auv recon mesh` and a step of `auv recon run`.
class MeshStage final : public StageWith<MeshStageOptions> {
 public:
  std::string name() const override { return "mesh"; }
  std::string usage() const override {
    return "<survey>   Poisson surface of the dense cloud, trimmed";
  }
  std::string surveyHelp() const override {
    return "survey folder (reads dense/fused.ply, writes mesh/)";
  }
  std::vector<std::filesystem::path> inputs(const Survey& survey) const override {
    return {survey.dense()};
  }
  std::vector<std::filesystem::path> outputs(const Survey& survey) const override {
    return {survey.mesh()};
  }
  StageReport runWith(const Survey& survey, const MeshStageOptions& options) const override;
};

}  // namespace auv::recon::mesh
