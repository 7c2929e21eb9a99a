#pragma once
// Ground truth of the rendered videos in COLMAP's text format, so a reconstruction can be
// compared with it directly (COLMAP model_aligner / model_comparer):
//   cameras.txt          CAMERA_ID MODEL WIDTH HEIGHT PARAMS[] (OPENCV: fx fy cx cy k1 k2 p1
//                        p2; FULL_OPENCV when k3 != 0), principal point in COLMAP's convention
//                        (the first pixel's centre at 0.5, OpenCV's cx + 0.5)
//   images_<camera>.txt  IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then an empty POINTS2D
//                        line; (Q, T) is world -> camera, NAME is "<video file>#<frame>".

#include <Eigen/Geometry>
#include <map>
#include <string>

#include "auv/sim/camera/camera_model.h"

namespace auv::sim {

/// One cameras.txt data line (without newline) for COLMAP camera `camera_id`.
std::string colmapCameraLine(int camera_id, const CameraIntrinsics& intrinsics);

/// Rewrites `path` with the given cameras (id -> line), keeping lines of other ids already in
/// the file (so rendering cameras one at a time accumulates them). `names` (id -> camera name)
/// go into the header comment. Written to a temporary file and renamed into place.
void updateColmapCameras(const std::string& path, const std::map<int, std::string>& lines,
                         const std::map<int, std::string>& names);

/// One images.txt entry (two lines, with the trailing newline) of a camera -> world pose.
std::string colmapImageEntry(int64_t image_id, const Eigen::Isometry3d& camera_to_world,
                             int camera_id, const std::string& name);

}  // namespace auv::sim
