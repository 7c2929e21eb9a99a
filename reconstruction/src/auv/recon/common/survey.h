#pragma once
// The survey folder of one reconstruction job (docs/design.md §6): each stage reads
// the previous stage's folder and writes its own, so any stage can be re-run or stopped early.
//
//   survey/
//     recordings/<camera>/...        pulled (or imported) video + frame-time sidecars
//     calibration/<camera>.yaml      OpenCV FileStorage intrinsics + distortion
//     calibration/<camera>.prior.yaml  a starting guess of them (`auv recon import`)
//     keyframes/<camera>/*.png       selected frames + index.csv
//     corrected/<camera>/*.png       colour corrected, undistorted (+ corrected/<camera>.yaml)
//     sparse/                        COLMAP text model, points.ply, cameras.ply
//                                    (+ <camera>.yaml: self-calibrated intrinsics)
//     sparse-partial/                the same, of a partial result not accepted (sfm)
//     undistorted/                   pinhole images + sparse/ when sfm estimated a lens
//                                    distortion (sfm/undistorted_model.h)
//     dense/                         depth maps, fused.ply
//     mesh/                          mesh.ply (Poisson, trimmed)
//     textured/                      model.obj + model.mtl + atlas PNGs
//     report.json                    what each stage did: counts, timings

#include <filesystem>
#include <string>
#include <vector>

namespace auv::recon {

class Survey {
 public:
  /// `root` need not exist yet (a stage creates what it writes).
  explicit Survey(std::filesystem::path root);

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path recordings() const { return root_ / "recordings"; }
  std::filesystem::path calibration() const { return root_ / "calibration"; }
  std::filesystem::path calibrationFile(const std::string& camera) const {
    return calibration() / (camera + ".yaml");
  }
  std::filesystem::path keyframes() const { return root_ / "keyframes"; }
  std::filesystem::path corrected() const { return root_ / "corrected"; }
  std::filesystem::path sparse() const { return root_ / "sparse"; }
  std::filesystem::path undistorted() const { return root_ / "undistorted"; }
  std::filesystem::path dense() const { return root_ / "dense"; }
  std::filesystem::path mesh() const { return root_ / "mesh"; }
  std::filesystem::path textured() const { return root_ / "textured"; }
  std::filesystem::path report() const { return root_ / "report.json"; }

  /// The pinhole model and its images that dense matching and texturing read: undistorted/
  /// (its sparse/ and images) when sfm wrote it, else sparse/ and corrected/.
  struct PinholeWorkspace {
    std::filesystem::path model, images;
  };
  PinholeWorkspace pinholeWorkspace() const;

  /// The camera ids of a stage folder: its sub-folders, sorted (hidden ones skipped).
  /// Throws StageError(stage, ...) when `folder` is missing or has none.
  static std::vector<std::string> cameraFolders(const std::filesystem::path& folder,
                                                const std::string& stage);

  /// Throws StageError(stage, "<what> not found: <path> (run `auv recon <producer>` first)").
  static void requireExists(const std::filesystem::path& path, const std::string& stage,
                            const std::string& producer);

 private:
  std::filesystem::path root_;
};

/// Simulation times covered by the survey's recordings (sim_time_s of the frame sidecars);
/// false when there are none (a real camera's sidecars leave sim_time_s empty).
bool recordedSimSpan(const Survey& survey, double& first, double& last);

/// Files of `folder` with one of `extensions` (lower case, with the dot), sorted by name.
std::vector<std::filesystem::path> listFiles(const std::filesystem::path& folder,
                                             const std::vector<std::string>& extensions);

}  // namespace auv::recon
