#pragma once
// Optional metric scale and gravity from the vehicle's navigation (issue 6 item 5; the paper's
// model had an arbitrary scale): the camera centres of the registered keyframes are aligned to
// the navigation positions at the keyframes' times by a similarity (Umeyama), which puts the
// model in metres in the navigation frame (NED: z down along gravity).
//
// Reads keyframes/<camera>/index.csv (file, ..., sim_time_s) for each image's time and a TUM
// trajectory "t x y z qx qy qz qw" (the simulator's <run>/ground_truth/navigation.tum, the
// vehicle's navigation estimate; or trajectory.tum, the truth). The camera's lever arm on the
// vehicle (tens of cm) is not modelled: it is absorbed as noise in the fit.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "auv/recon/common/trajectory.h"
#include "auv/recon/scene/reconstruction.h"
#include "auv/recon/sfm/alignment.h"

namespace auv::recon::sfm {

// The TUM reader lives in common/ (the match stage uses it too).
using recon::positionAt;
using recon::readTumTrajectory;
using recon::TimedPosition;

/// Image name "<camera>/<file>" -> sim_time_s from keyframes/<camera>/index.csv of each
/// camera folder present; images with an empty time are left out. Missing index files give no
/// entries. Throws std::runtime_error naming the file and line for a malformed index.
std::map<std::string, double> readKeyframeTimes(const std::filesystem::path& keyframes_folder,
                                                const std::vector<std::string>& cameras);

struct NavigationAlignment {
  bool applied = false;
  std::string reason;  ///< why not, when not applied
  size_t images = 0;   ///< images with a navigation position
  Similarity similarity;
  double rms_m = 0;  ///< camera centres to navigation positions after the alignment, m
};

/// Aligns `reconstruction` (in place) to the navigation when at least `min_images` registered
/// images have a time inside the trajectory and their centres are not collinear.
NavigationAlignment alignToNavigation(scene::Reconstruction& reconstruction,
                                      const std::map<std::string, double>& image_times,
                                      const std::vector<TimedPosition>& trajectory,
                                      size_t min_images = 3);

}  // namespace auv::recon::sfm
