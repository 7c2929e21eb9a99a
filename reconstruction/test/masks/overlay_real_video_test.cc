// The static-overlay detector on a real video nobody here made: Debian opencv-doc's `vtest.avi`,
// a fixed surveillance camera over a street with people walking. Most of its pixels are static
// and sharp, just like an overlay's: the detector must refuse the camera, not mask the street.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "auv/recon/overlay/overlay_detector.h"

namespace fs = std::filesystem;
using namespace auv::recon;

TEST(OverlayRealVideo, AFixedSurveillanceCameraIsRefusedNotMaskedWholesale) {
  const fs::path video = "/usr/share/doc/opencv-doc/examples/data/vtest.avi";
  if (!fs::exists(video)) {
    GTEST_SKIP() << video << " absent: install opencv-doc (scripts/install-deps.sh)";
  }
  try {
    const overlay::OverlayDetection detection =
        overlay::detectInVideos({video}, overlay::OverlayOptions());
    FAIL() << "a fixed camera gave a mask hiding " << 100 * detection.masked_fraction
           << " % of the image (moving " << detection.moving_fraction << ")";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("barely moves"), std::string::npos) << e.what();
  }
}
