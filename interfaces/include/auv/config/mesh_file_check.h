#pragma once
// Files Open3D 0.16 must not be given: its PLY reader (rply) and OBJ reader (ASSIMP 5.2.5) trust
// the file, and some malformed files crash them, exhaust the memory or never end (found by
// fuzzing, docs/reliability.md "Fuzzing"). Each check reads the file as that reader would and
// names the first such problem; "" when the reader may be given it (it may still fail by
// itself, cleanly). Shared by the simulator's world meshes and the reconstruction's stages.

#include <string>

namespace auv::config {

/// The PLY file at `path`: counts the data cannot hold, elements without properties, lists of
/// lists, and (`check_faces`) faces outside 3..255 corners or with a corner past the vertices.
std::string plyFileProblem(const std::string& path, bool check_faces);

/// The OBJ file at `path` and the material libraries it may read: faces of one or two corners,
/// corners of four indices, statements before the first `newmtl` of a material library.
std::string objFileProblem(const std::string& path);

}  // namespace auv::config
