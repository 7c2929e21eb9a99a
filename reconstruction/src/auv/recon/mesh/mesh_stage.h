#pragma once
// `auv recon mesh`: <survey>/dense/fused.ply -> <survey>/mesh/mesh.ply (Poisson, trimmed) and
// mesh/mesh_untrimmed.ply (for inspection), report.json section "mesh" (README.md).

#include <filesystem>
#include <string>

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include "auv/recon/common/option_set.h"
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

struct MeshStageSummary {
  TrimStats stats;
  size_t cloud_points = 0;
  double area_untrimmed = 0, area = 0;  ///< m^2
  double seconds = 0;
};

/// Reads a point cloud (PLY), throwing StageError("mesh", ...) naming the file when it is
/// missing or unreadable.
open3d::geometry::PointCloud readCloud(const std::filesystem::path& file);

/// Writes a mesh (positions, vertex normals and colours when present, triangles) as binary PLY
/// through a temporary name.
void writeMeshPly(const std::filesystem::path& file, const open3d::geometry::TriangleMesh& mesh);

/// Reads a mesh PLY; StageError(stage, ...) naming the file when missing, unreadable or empty.
open3d::geometry::TriangleMesh readMesh(const std::filesystem::path& file,
                                        const std::string& stage);

/// The whole stage on a survey folder. The mesh folder is replaced only when everything is
/// written (StagedOutput): a failure leaves the previous mesh/ as it was.
MeshStageSummary runMeshStage(const Survey& survey, const MeshStageOptions& options);

}  // namespace auv::recon::mesh
