#pragma once
// Reading point clouds and meshes (PLY, OBJ: Open3D's readers) and writing meshes as PLY
// (ply.h), shared by the stages: mesh reads the dense cloud, texture the mesh, evaluate and
// figures the clouds and meshes of a survey and the simulator's world mesh.

#include <filesystem>
#include <string>

namespace open3d::geometry {
class PointCloud;
class TriangleMesh;
}  // namespace open3d::geometry

namespace auv::recon::scene {

/// Reads a point cloud (PLY; the format from the extension); false when it cannot.
/// `drop_non_finite`: points with NaN or infinite coordinates are left out.
bool readPointCloud(const std::filesystem::path& file, open3d::geometry::PointCloud& cloud,
                    bool drop_non_finite = false);
/// Reads a mesh (PLY, OBJ), as written (no post-processing); false when it cannot.
bool readTriangleMesh(const std::filesystem::path& file, open3d::geometry::TriangleMesh& mesh);

/// A stage's input cloud: StageError(stage, ...) naming the file when it is missing (made by
/// `producer`) or unreadable. Non-finite points are dropped.
open3d::geometry::PointCloud readCloud(const std::filesystem::path& file, const std::string& stage,
                                       const std::string& producer);
/// A stage's input mesh: StageError(stage, ...) naming the file when it is missing (made by the
/// `mesh` stage), unreadable or without triangles. A PLY or OBJ is checked before Open3D reads
/// it (its readers trust the file): a face corner past the vertices, a count the file cannot
/// hold, a material statement before the first newmtl and the like are such errors, as they
/// are false for readTriangleMesh.
open3d::geometry::TriangleMesh readMesh(const std::filesystem::path& file,
                                        const std::string& stage);

/// Writes a mesh (positions, vertex normals and colours when present, triangles) as binary PLY
/// through a temporary name (writePly).
void writeMeshPly(const std::filesystem::path& file, const open3d::geometry::TriangleMesh& mesh);

}  // namespace auv::recon::scene
