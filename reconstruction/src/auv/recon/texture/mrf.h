#pragma once
// A multi-label Markov random field with a Potts smoothness term, minimised by alpha-expansion
// graph cuts (Boykov, Veksler, Zabih, "Fast approximate energy minimization via graph cuts",
// PAMI 2001), each expansion move a minimum cut by Boost.Graph's Boykov-Kolmogorov max-flow
// (Kolmogorov and Zabih's construction of the binary move energy, PAMI 2004).
//
//   E(l) = sum_n D_n(l_n) + w * sum_{(n, m) in edges} [l_n != l_m]
//
// Each node has its own candidate labels (the views that see a face); other labels are
// forbidden. Nodes without candidates stay unlabelled (kNoLabel) and their edges cost nothing.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace auv::recon::texture {

constexpr int kNoLabel = -1;

struct PottsProblem {
  /// Per node: (label, data cost >= 0), sorted by label, labels unique.
  std::vector<std::vector<std::pair<int, float>>> costs;
  /// Neighbouring node pairs (each once).
  std::vector<std::pair<int, int>> edges;
  /// Potts weight w of a label change across an edge (>= 0).
  double smoothness = 1.0;

  size_t numNodes() const { return costs.size(); }
  /// D_n(label), or +inf when `label` is not a candidate of `node`.
  double dataCost(int node, int label) const;
};

/// Energy of a labelling (+inf when some node has a forbidden label).
double energy(const PottsProblem& problem, const std::vector<int>& labels);

/// Each node takes its cheapest candidate (kNoLabel without candidates): the greedy pick that
/// ignores smoothness.
std::vector<int> greedyLabels(const PottsProblem& problem);

/// Edges whose two nodes are labelled with different labels.
size_t countSeams(const PottsProblem& problem, const std::vector<int>& labels);

struct ExpansionResult {
  std::vector<int> labels;
  double initial_energy = 0, energy = 0;
  int cycles = 0;    ///< passes over all labels
  size_t moves = 0;  ///< expansion moves that lowered the energy
};

/// Alpha-expansion from `initial` (greedy when empty) until a full cycle over the labels
/// lowers the energy by less than a relative 1e-6, or `max_cycles`. The energy never increases.
ExpansionResult alphaExpansion(const PottsProblem& problem, std::vector<int> initial = {},
                               int max_cycles = 8);

}  // namespace auv::recon::texture
