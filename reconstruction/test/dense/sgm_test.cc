// SGM path aggregation on hand-made cost volumes with known answers.
#include "auv/recon/dense/sgm.h"

#include <gtest/gtest.h>

namespace auv::recon::dense {
namespace {

int winner(const LabelVolume& volume, const std::vector<uint16_t>& values, size_t p) {
  int best = 0;
  for (int i = 1; i < volume.count[p]; ++i) {
    if (values[p * volume.stride + i] < values[p * volume.stride + best]) best = i;
  }
  return volume.low[p] + best;
}

// A row whose true label is 5 everywhere; one pixel's cost prefers label 9 alone. Half of the
// pixels search labels [0, 10), the others [3, 13): labels are compared in the global grid.
TEST(Sgm, PathsOverruleAnIsolatedWrongMinimumAcrossShiftedRanges) {
  LabelVolume volume;
  volume.reset(21, 3, 10);
  const cv::Mat guide(3, 21, CV_32F, cv::Scalar(100));
  for (size_t p = 0; p < volume.pixels(); ++p) {
    volume.low[p] = (p % 2) ? 3 : 0;
    volume.count[p] = 10;
    for (int i = 0; i < 10; ++i) {
      const int label = volume.low[p] + i;
      volume.costs(p)[i] = static_cast<uint16_t>(label == 5 ? 100 : 300);
    }
  }
  const size_t noisy = 21 + 10;  // row 1, column 10
  volume.costs(noisy)[9 - volume.low[noisy]] = 80;
  volume.costs(noisy)[5 - volume.low[noisy]] = 200;
  EXPECT_EQ(winner(volume, volume.cost, noisy), 9) << "the raw cost prefers the wrong label";

  const SgmPenalties penalties{20, 200, 10, 8};
  const std::vector<uint16_t> sums = aggregatePaths(volume, guide, penalties);
  for (size_t p = 0; p < volume.pixels(); ++p) EXPECT_EQ(winner(volume, sums, p), 5) << p;
}

// Two halves at different labels: a large step between them is kept (P2 paid once), and a
// pixel with no labels (count 0) breaks the paths without disturbing its neighbours.
TEST(Sgm, KeepsADiscontinuityAndSkipsUnmatchedPixels) {
  LabelVolume volume;
  volume.reset(20, 4, 16);
  const cv::Mat guide(4, 20, CV_32F, cv::Scalar(50));
  for (size_t p = 0; p < volume.pixels(); ++p) {
    const int x = static_cast<int>(p % 20);
    const int truth = x < 10 ? 2 : 13;
    volume.low[p] = 0;
    volume.count[p] = 16;
    for (int i = 0; i < 16; ++i) volume.costs(p)[i] = static_cast<uint16_t>(i == truth ? 0 : 400);
  }
  const size_t hole = 2 * 20 + 5;
  volume.count[hole] = 0;
  const std::vector<uint16_t> sums = aggregatePaths(volume, guide, SgmPenalties{24, 160, 10, 8});
  for (size_t p = 0; p < volume.pixels(); ++p) {
    if (p == hole) continue;
    EXPECT_EQ(winner(volume, sums, p), (p % 20) < 10 ? 2 : 13) << p;
  }
}

TEST(Sgm, RejectsAGuideOfTheWrongSize) {
  LabelVolume volume;
  volume.reset(8, 8, 4);
  const cv::Mat guide(4, 4, CV_32F, cv::Scalar(0));
  EXPECT_THROW(aggregatePaths(volume, guide, SgmPenalties{}), cv::Exception);
}

}  // namespace
}  // namespace auv::recon::dense
