#include "auv/recon/texture/mrf.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

// Boost.Graph's edge iterators trip GCC 12's -Wmaybe-uninitialized (a false positive in
// boost/graph/detail/adj_list_edge_iterator.hpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>

namespace auv::recon::texture {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// Capacities are integers (exact max-flow, no floating-point stalls): costs x kScale.
constexpr double kScale = 1 << 20;

using Traits = boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
struct EdgeProperties {
  int64_t capacity = 0;
  int64_t residual = 0;
  Traits::edge_descriptor reverse;
};
using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS, boost::no_property,
                                    EdgeProperties>;

/// Adds the pair of mutually reverse edges a->b (capacity ab) and b->a (capacity ba).
void addEdgePair(Graph& graph, size_t a, size_t b, int64_t ab, int64_t ba) {
  const auto forward = boost::add_edge(a, b, graph).first;
  const auto backward = boost::add_edge(b, a, graph).first;
  graph[forward].capacity = ab;
  graph[backward].capacity = ba;
  graph[forward].reverse = backward;
  graph[backward].reverse = forward;
}

int64_t capacity(double cost) { return static_cast<int64_t>(std::llround(cost * kScale)); }

}  // namespace

double PottsProblem::dataCost(int node, int label) const {
  const auto& candidates = costs[node];
  const auto it =
      std::lower_bound(candidates.begin(), candidates.end(), label,
                       [](const std::pair<int, float>& c, int l) { return c.first < l; });
  if (it == candidates.end() || it->first != label) return kInfinity;
  return it->second;
}

double energy(const PottsProblem& problem, const std::vector<int>& labels) {
  double total = 0;
  for (size_t n = 0; n < problem.numNodes(); ++n) {
    if (labels[n] == kNoLabel) {
      if (!problem.costs[n].empty()) return kInfinity;  // a seen node must be labelled
      continue;
    }
    total += problem.dataCost(static_cast<int>(n), labels[n]);
  }
  return total + problem.smoothness * static_cast<double>(countSeams(problem, labels));
}

std::vector<int> greedyLabels(const PottsProblem& problem) {
  std::vector<int> labels(problem.numNodes(), kNoLabel);
  for (size_t n = 0; n < problem.numNodes(); ++n) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& [label, cost] : problem.costs[n]) {
      if (cost < best) {
        best = cost;
        labels[n] = label;
      }
    }
  }
  return labels;
}

size_t countSeams(const PottsProblem& problem, const std::vector<int>& labels) {
  size_t seams = 0;
  for (const auto& [a, b] : problem.edges) {
    if (labels[a] != kNoLabel && labels[b] != kNoLabel && labels[a] != labels[b]) ++seams;
  }
  return seams;
}

ExpansionResult alphaExpansion(const PottsProblem& problem, std::vector<int> initial,
                               int max_cycles) {
  const size_t num_nodes = problem.numNodes();
  ExpansionResult result;
  result.labels = initial.empty() ? greedyLabels(problem) : std::move(initial);
  result.initial_energy = energy(problem, result.labels);
  result.energy = result.initial_energy;

  // Nodes per label and neighbours per node.
  int max_label = -1;
  for (const auto& candidates : problem.costs) {
    if (!candidates.empty()) max_label = std::max(max_label, candidates.back().first);
  }
  std::vector<std::vector<int>> nodes_of_label(max_label + 1);
  for (size_t n = 0; n < num_nodes; ++n) {
    for (const auto& candidate : problem.costs[n]) {
      nodes_of_label[candidate.first].push_back(static_cast<int>(n));
    }
  }
  std::vector<std::vector<int>> neighbours(num_nodes);
  for (const auto& [a, b] : problem.edges) {
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  const double w = problem.smoothness;
  std::vector<int> graph_index(num_nodes, -1);

  for (int cycle = 0; cycle < max_cycles; ++cycle) {
    const double cycle_start = result.energy;
    for (int alpha = 0; alpha <= max_label; ++alpha) {
      const std::vector<int>& members = nodes_of_label[alpha];
      if (members.empty()) continue;
      // Binary move per member: x = 0 keeps its label, x = 1 takes alpha. Nodes that cannot
      // take alpha keep their label and enter the members' unary terms.
      std::vector<double> e0(members.size(), 0.0), e1(members.size(), 0.0);
      for (size_t i = 0; i < members.size(); ++i) graph_index[members[i]] = static_cast<int>(i);
      Graph graph(members.size() + 2);
      const size_t source = members.size(), sink = members.size() + 1;
      for (size_t i = 0; i < members.size(); ++i) {
        const int n = members[i];
        const int current = result.labels[n];
        e0[i] += problem.dataCost(n, current);
        e1[i] += problem.dataCost(n, alpha);
        for (int m : neighbours[n]) {
          const int other = result.labels[m];
          if (other == kNoLabel) continue;  // unseen neighbours: no smoothness term
          const int j = graph_index[m];
          if (j < 0) {  // fixed neighbour
            e0[i] += w * (current != other);
            e1[i] += w * (alpha != other);
          } else if (n < m) {  // each pair once: E(x_n, x_m) with A, B, C, D
            const double A = w * (current != other), B = w * (current != alpha),
                         C = w * (alpha != other), D = 0.0;
            // E = A + (C - A) x_n + (D - C) x_m + (B + C - A - D)(1 - x_n) x_m
            e1[i] += C - A;
            e0[j] += C - D;                     // (D - C) x_m == (C - D)(1 - x_m) - (C - D)
            const double pair = B + C - A - D;  // >= 0: Potts is a metric
            addEdgePair(graph, i, static_cast<size_t>(j), capacity(pair), 0);
          }
        }
      }
      for (size_t i = 0; i < members.size(); ++i) {
        const double low = std::min(e0[i], e1[i]);
        // x = 1 (sink side) cuts source->i; x = 0 (source side) cuts i->sink.
        addEdgePair(graph, source, i, capacity(e1[i] - low), 0);
        addEdgePair(graph, i, sink, capacity(e0[i] - low), 0);
      }
      std::vector<boost::default_color_type> color(boost::num_vertices(graph));
      boost::boykov_kolmogorov_max_flow(
          graph, boost::get(&EdgeProperties::capacity, graph),
          boost::get(&EdgeProperties::residual, graph), boost::get(&EdgeProperties::reverse, graph),
          boost::make_iterator_property_map(color.begin(), boost::get(boost::vertex_index, graph)),
          boost::get(boost::vertex_index, graph), source, sink);
      // The move's energy change, over the switched nodes and their edges only.
      std::vector<int> switched;
      for (size_t i = 0; i < members.size(); ++i) {
        // Black: the source's tree (x = 0, keep); everything else is on the sink's side.
        if (color[i] != boost::black_color && result.labels[members[i]] != alpha) {
          switched.push_back(members[i]);
        }
      }
      double delta = 0;
      for (int n : switched) {
        delta += problem.dataCost(n, alpha) - problem.dataCost(n, result.labels[n]);
        graph_index[n] = -2;  // marks switched nodes
      }
      for (int n : switched) {
        for (int m : neighbours[n]) {
          const int other = result.labels[m];
          if (other == kNoLabel) continue;
          const bool m_switched = graph_index[m] == -2;
          if (m_switched && m < n) continue;  // each edge between switched nodes once
          const int after = m_switched ? alpha : other;
          delta += w * ((alpha != after) - (result.labels[n] != other));
        }
      }
      for (int n : members) graph_index[n] = -1;
      if (!switched.empty() && delta < -1e-9) {
        for (int n : switched) result.labels[n] = alpha;
        result.energy += delta;
        ++result.moves;
      }
    }
    result.energy = energy(problem, result.labels);  // no drift from the summed deltas
    result.cycles = cycle + 1;
    if (cycle_start - result.energy <= 1e-6 * std::max(1.0, std::abs(cycle_start))) break;
  }
  return result;
}

}  // namespace auv::recon::texture
