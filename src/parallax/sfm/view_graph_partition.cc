#include "parallax/sfm/view_graph_partition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "parallax/util/check.h"

namespace parallax {

void ViewGraphPartitionOptions::Check() const {
  PARALLAX_CHECK_GE(max_cluster_images, 2);
  PARALLAX_CHECK_GE(overlap_images, 0);
  PARALLAX_CHECK(min_split_fraction > 0 && min_split_fraction <= 0.5);
  PARALLAX_CHECK_GE(max_lanczos_steps, 2);
}

namespace {

// The graph over node indices 0..n-1 (images in id order), edges merged and symmetric.
struct WeightedGraph {
  std::vector<std::vector<std::pair<int, double>>> neighbors;
};

WeightedGraph BuildGraph(const std::vector<ViewGraphEdge>& edges, std::vector<image_t>* image_ids) {
  for (const ViewGraphEdge& edge : edges) {
    if (edge.image_id1 == edge.image_id2 || !(edge.weight > 0)) continue;
    image_ids->push_back(edge.image_id1);
    image_ids->push_back(edge.image_id2);
  }
  std::sort(image_ids->begin(), image_ids->end());
  image_ids->erase(std::unique(image_ids->begin(), image_ids->end()), image_ids->end());
  const auto index_of = [&](image_t image_id) {
    return static_cast<int>(std::lower_bound(image_ids->begin(), image_ids->end(), image_id) -
                            image_ids->begin());
  };
  std::map<std::pair<int, int>, double> merged;
  for (const ViewGraphEdge& edge : edges) {
    if (edge.image_id1 == edge.image_id2 || !(edge.weight > 0)) continue;
    const int a = index_of(edge.image_id1);
    const int b = index_of(edge.image_id2);
    merged[{std::min(a, b), std::max(a, b)}] += edge.weight;
  }
  WeightedGraph graph;
  graph.neighbors.resize(image_ids->size());
  for (const auto& [nodes, weight] : merged) {
    graph.neighbors[nodes.first].emplace_back(nodes.second, weight);
    graph.neighbors[nodes.second].emplace_back(nodes.first, weight);
  }
  return graph;
}

// The connected components of the subgraph induced by `nodes` (sorted), each sorted.
std::vector<std::vector<int>> Components(const WeightedGraph& graph, const std::vector<int>& nodes,
                                         std::vector<int>* scratch_label) {
  // Every scratch entry is -1 between calls; -3 marks a subgraph node not yet reached.
  std::vector<int>& label = *scratch_label;
  for (const int node : nodes) label[node] = -3;
  std::vector<std::vector<int>> components;
  for (const int start : nodes) {
    if (label[start] != -3) continue;
    std::vector<int> component = {start};
    label[start] = 1;
    for (size_t i = 0; i < component.size(); ++i) {
      for (const auto& [next, weight] : graph.neighbors[component[i]]) {
        if (label[next] == -3) {
          label[next] = 1;
          component.push_back(next);
        }
      }
    }
    std::sort(component.begin(), component.end());
    components.push_back(std::move(component));
  }
  for (const int node : nodes) label[node] = -1;
  return components;
}

// The Fiedler vector of the connected subgraph on `nodes`: the second eigenvector of
// D^-1/2 W D^-1/2 by Lanczos with full reorthogonalisation, deflated against the first
// (sqrt of the degrees), returned as D^-1/2 u so that its sweep orders the normalised cut.
Eigen::VectorXd FiedlerVector(const WeightedGraph& graph, const std::vector<int>& nodes,
                              int max_steps, std::vector<int>* scratch_local) {
  const int n = static_cast<int>(nodes.size());
  std::vector<int>& local = *scratch_local;
  for (int i = 0; i < n; ++i) local[nodes[i]] = i;
  Eigen::VectorXd degree = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    for (const auto& [next, weight] : graph.neighbors[nodes[i]]) {
      if (local[next] >= 0) degree[i] += weight;
    }
  }
  const Eigen::VectorXd inv_sqrt_degree = degree.cwiseSqrt().cwiseInverse();
  const Eigen::VectorXd trivial = degree.cwiseSqrt().normalized();
  const auto multiply = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) {
      double sum = 0;
      for (const auto& [next, weight] : graph.neighbors[nodes[i]]) {
        const int j = local[next];
        if (j >= 0) sum += weight * inv_sqrt_degree[j] * x[j];
      }
      y[i] = inv_sqrt_degree[i] * sum;
    }
    return y;
  };

  const int num_steps = std::min(max_steps, n - 1);
  Eigen::MatrixXd basis(n, num_steps);
  std::vector<double> alpha, beta;
  // A fixed start (not the run's generator): the partition depends on the graph alone.
  std::mt19937_64 generator(0x5eed);
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = static_cast<double>(generator() >> 11) * 0x1.0p-53 - 0.5;
  const auto orthogonalize = [&](Eigen::VectorXd* v, int num_basis) {
    for (int pass = 0; pass < 2; ++pass) {
      *v -= trivial * trivial.dot(*v);
      if (num_basis > 0) {
        *v -= basis.leftCols(num_basis) * (basis.leftCols(num_basis).transpose() * *v);
      }
    }
  };
  orthogonalize(&q, 0);
  q.normalize();
  for (int step = 0; step < num_steps; ++step) {
    basis.col(step) = q;
    Eigen::VectorXd w = multiply(q);
    alpha.push_back(q.dot(w));
    orthogonalize(&w, step + 1);
    const double norm = w.norm();
    if (step + 1 == num_steps || norm < 1e-12) break;  // Done, or an invariant subspace.
    beta.push_back(norm);
    q = w / norm;
  }
  const int m = static_cast<int>(alpha.size());
  Eigen::MatrixXd tridiagonal = Eigen::MatrixXd::Zero(m, m);
  for (int i = 0; i < m; ++i) tridiagonal(i, i) = alpha[i];
  for (int i = 0; i + 1 < m; ++i) tridiagonal(i, i + 1) = tridiagonal(i + 1, i) = beta[i];
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(tridiagonal);
  const Eigen::VectorXd u = basis.leftCols(m) * solver.eigenvectors().col(m - 1);
  for (const int node : nodes) local[node] = -1;
  return u.cwiseProduct(inv_sqrt_degree);
}

// Splits a connected subgraph in two at the sweep position of the Fiedler vector that gives
// the smallest normalised cut among the balanced ones.
std::pair<std::vector<int>, std::vector<int>> Bisect(const WeightedGraph& graph,
                                                     const std::vector<int>& nodes,
                                                     const ViewGraphPartitionOptions& options,
                                                     std::vector<int>* scratch_local) {
  const int n = static_cast<int>(nodes.size());
  const Eigen::VectorXd fiedler =
      FiedlerVector(graph, nodes, options.max_lanczos_steps, scratch_local);
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return fiedler[a] < fiedler[b]; });

  std::vector<int>& local = *scratch_local;
  for (int i = 0; i < n; ++i) local[nodes[i]] = i;
  std::vector<double> degree(n, 0.0);
  double total_volume = 0;
  for (int i = 0; i < n; ++i) {
    for (const auto& [next, weight] : graph.neighbors[nodes[i]]) {
      if (local[next] >= 0) degree[i] += weight;
    }
    total_volume += degree[i];
  }
  const int min_side = std::max(1, static_cast<int>(std::ceil(options.min_split_fraction * n)));
  std::vector<char> in_first(n, 0);
  double cut = 0, volume = 0, best_ncut = std::numeric_limits<double>::infinity();
  int best_size = n / 2;
  for (int k = 0; k + 1 < n; ++k) {
    const int i = order[k];
    double to_first = 0;
    for (const auto& [next, weight] : graph.neighbors[nodes[i]]) {
      const int j = local[next];
      if (j >= 0 && in_first[j]) to_first += weight;
    }
    in_first[i] = 1;
    cut += degree[i] - 2 * to_first;
    volume += degree[i];
    const int size = k + 1;
    if (size < min_side || n - size < min_side) continue;
    const double ncut = cut / volume + cut / (total_volume - volume);
    if (ncut < best_ncut) {
      best_ncut = ncut;
      best_size = size;
    }
  }
  for (const int node : nodes) local[node] = -1;
  std::vector<int> first, second;
  for (int k = 0; k < n; ++k) (k < best_size ? first : second).push_back(nodes[order[k]]);
  std::sort(first.begin(), first.end());
  std::sort(second.begin(), second.end());
  return {first, second};
}

// Adds to every cluster the images of each neighbouring cluster most strongly linked to it.
void AddOverlap(const WeightedGraph& graph, int overlap_images,
                std::vector<std::vector<int>>* clusters) {
  std::vector<int> cluster_of(graph.neighbors.size(), -1);
  for (size_t c = 0; c < clusters->size(); ++c) {
    for (const int node : (*clusters)[c]) cluster_of[node] = static_cast<int>(c);
  }
  std::vector<std::vector<int>> expanded = *clusters;
  for (size_t c = 0; c < clusters->size(); ++c) {
    // Per neighbouring cluster: its images linked to this one, with the total weight.
    std::map<int, std::map<int, double>> linked;
    for (const int node : (*clusters)[c]) {
      for (const auto& [next, weight] : graph.neighbors[node]) {
        if (cluster_of[next] != static_cast<int>(c)) linked[cluster_of[next]][next] += weight;
      }
    }
    for (const auto& [other, weights] : linked) {
      std::vector<std::pair<double, int>> ranked;
      for (const auto& [node, weight] : weights) ranked.emplace_back(weight, node);
      std::stable_sort(ranked.begin(), ranked.end(),
                       [](const auto& a, const auto& b) { return a.first > b.first; });
      for (size_t i = 0; i < ranked.size() && static_cast<int>(i) < overlap_images; ++i) {
        expanded[c].push_back(ranked[i].second);
      }
    }
    std::sort(expanded[c].begin(), expanded[c].end());
  }
  *clusters = std::move(expanded);
}

}  // namespace

std::vector<std::vector<image_t>> PartitionViewGraph(const ViewGraphPartitionOptions& options,
                                                     const std::vector<ViewGraphEdge>& edges) {
  options.Check();
  std::vector<image_t> image_ids;
  const WeightedGraph graph = BuildGraph(edges, &image_ids);
  const int num_nodes = static_cast<int>(image_ids.size());
  std::vector<int> scratch(num_nodes, -1);
  std::vector<int> all(num_nodes);
  for (int i = 0; i < num_nodes; ++i) all[i] = i;

  std::vector<std::vector<int>> leaves;
  std::vector<std::vector<int>> pending = Components(graph, all, &scratch);
  while (!pending.empty()) {
    std::vector<int> nodes = std::move(pending.back());
    pending.pop_back();
    if (static_cast<int>(nodes.size()) <= options.max_cluster_images) {
      leaves.push_back(std::move(nodes));
      continue;
    }
    auto [first, second] = Bisect(graph, nodes, options, &scratch);
    // A side of a cut need not be connected: its pieces are split on their own.
    for (std::vector<int>* side : {&first, &second}) {
      for (std::vector<int>& piece : Components(graph, *side, &scratch))
        pending.push_back(std::move(piece));
    }
  }
  AddOverlap(graph, options.overlap_images, &leaves);

  std::vector<std::vector<image_t>> clusters;
  for (const std::vector<int>& leaf : leaves) {
    std::vector<image_t> cluster;
    for (const int node : leaf) cluster.push_back(image_ids[node]);
    clusters.push_back(std::move(cluster));
  }
  std::sort(clusters.begin(), clusters.end());
  return clusters;
}

}  // namespace parallax
