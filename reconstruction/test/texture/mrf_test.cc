// Alpha-expansion against exhaustive search on small Potts problems, and the rasteriser.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "auv/recon/texture/mrf.h"
#include "auv/recon/texture/rasterizer.h"

using namespace auv::recon::texture;

namespace {

/// Random problem on a 3 x 3 grid of nodes, 3 labels, each node with 1-3 candidates.
PottsProblem randomProblem(std::mt19937& rng, double smoothness) {
  PottsProblem problem;
  problem.smoothness = smoothness;
  std::uniform_real_distribution<float> cost(0.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 2);
  problem.costs.resize(9);
  for (int n = 0; n < 9; ++n) {
    for (int l = 0; l < 3; ++l) {
      if (l == 0 || pick(rng) > 0) problem.costs[n].emplace_back(l, cost(rng));
    }
  }
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 3; ++x) {
      if (x + 1 < 3) problem.edges.emplace_back(y * 3 + x, y * 3 + x + 1);
      if (y + 1 < 3) problem.edges.emplace_back(y * 3 + x, (y + 1) * 3 + x);
    }
  }
  return problem;
}

double bruteForceMinimum(const PottsProblem& problem) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<int> labels(problem.numNodes(), 0);
  const int total = static_cast<int>(std::pow(3, problem.numNodes()));
  for (int code = 0; code < total; ++code) {
    int c = code;
    for (auto& l : labels) {
      l = c % 3;
      c /= 3;
    }
    best = std::min(best, energy(problem, labels));
  }
  return best;
}

}  // namespace

TEST(AlphaExpansion, MatchesExhaustiveSearchWithinThePottsBound) {
  std::mt19937 rng(3);
  int optimal = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const PottsProblem problem = randomProblem(rng, trial % 2 == 0 ? 0.3 : 0.8);
    const double minimum = bruteForceMinimum(problem);
    const std::vector<int> greedy = greedyLabels(problem);
    const ExpansionResult result = alphaExpansion(problem);
    EXPECT_LE(result.energy, energy(problem, greedy) + 1e-9);
    EXPECT_NEAR(result.energy, energy(problem, result.labels), 1e-9);
    // Boykov et al.: within a factor 2 of the optimum for Potts; in practice at it.
    EXPECT_LE(result.energy, 2 * minimum + 1e-9);
    EXPECT_GE(result.energy, minimum - 1e-9);
    for (size_t n = 0; n < problem.numNodes(); ++n) {
      EXPECT_TRUE(std::isfinite(problem.dataCost(static_cast<int>(n), result.labels[n])))
          << "forbidden label at node " << n;
    }
    optimal += result.energy <= minimum + 1e-6;
  }
  std::cout << "alpha-expansion reached the exhaustive optimum in " << optimal << " of 40"
            << std::endl;
  EXPECT_GE(optimal, 36);
}

TEST(AlphaExpansion, SmoothsANoisyChainThatGreedyBreaksUp) {
  // 200 nodes in a chain, two labels with nearly equal costs that alternate in sign: greedy
  // changes label at almost every edge, the MRF keeps one label.
  PottsProblem problem;
  problem.smoothness = 0.2;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(0.0f, 0.1f);
  for (int n = 0; n < 200; ++n) {
    problem.costs.push_back({{0, 0.45f + noise(rng)}, {1, 0.45f + noise(rng)}});
    if (n > 0) problem.edges.emplace_back(n - 1, n);
  }
  const std::vector<int> greedy = greedyLabels(problem);
  const ExpansionResult result = alphaExpansion(problem);
  EXPECT_GT(countSeams(problem, greedy), 50u);
  EXPECT_LE(countSeams(problem, result.labels), 2u);
  EXPECT_LT(result.energy, energy(problem, greedy));
}

TEST(AlphaExpansion, NodesWithoutCandidatesStayUnlabelled) {
  PottsProblem problem;
  problem.costs = {{{0, 0.1f}}, {}, {{1, 0.2f}, {0, 0.0f}}};
  std::sort(problem.costs[2].begin(), problem.costs[2].end());
  problem.edges = {{0, 1}, {1, 2}};
  const ExpansionResult result = alphaExpansion(problem);
  EXPECT_EQ(result.labels[1], kNoLabel);
  EXPECT_EQ(result.labels[0], 0);
  EXPECT_EQ(result.labels[2], 0);
}

TEST(Rasterizer, DepthAndNearestFaceOfTwoSquares) {
  // A square at z = 2 in front of a larger one at z = 4, camera at the origin looking along +z.
  std::vector<Eigen::Vector3d> vertices = {{-0.5, -0.5, 2}, {0.5, -0.5, 2}, {0.5, 0.5, 2},
                                           {-0.5, 0.5, 2},  {-3, -3, 4},    {3, -3, 4},
                                           {3, 3, 4},       {-3, 3, 4}};
  std::vector<Eigen::Vector3i> faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  ViewGeometry view;
  view.camera = auv::recon::scene::Camera::pinhole(1, 101, 101, 50, 50, 50, 50);
  const RasterBuffers buffers = rasterize(vertices, faces, view);
  EXPECT_NEAR(buffers.depth(50, 50), 2.0, 1e-5);
  EXPECT_TRUE(buffers.face(50, 50) == 0 || buffers.face(50, 50) == 1);
  // Pixel 30 px off the centre: x/z = 0.6 -> beyond the small square (0.25 at z = 2).
  EXPECT_NEAR(buffers.depth(50, 80), 4.0, 1e-5);
  EXPECT_GE(buffers.face(50, 80), 2);
  // The small square covers |x| <= 0.5 / 2 * 50 = 12.5 px around the centre.
  EXPECT_NEAR(buffers.depth(50, 62), 2.0, 1e-5);
  EXPECT_NEAR(buffers.depth(50, 63), 4.0, 1e-5);
  // Perspective-correct barycentrics recover the surface point.
  const Eigen::Vector3d w = barycentricAt(vertices, faces[2], view, Eigen::Vector2d(80, 40));
  const Eigen::Vector3d p = w(0) * vertices[4] + w(1) * vertices[5] + w(2) * vertices[6];
  EXPECT_NEAR(p.z(), 4.0, 1e-9);
  EXPECT_NEAR(p.x() / p.z(), 30.0 / 50.0, 1e-9);
  EXPECT_NEAR(p.y() / p.z(), -10.0 / 50.0, 1e-9);
}
