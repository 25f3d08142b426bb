// The pairwise consistency check (pairwise_consistency.h; thesis sec. 4.3.3.1).
#include "apps/flag/pairwise_consistency.h"

#include <Eigen/LU>
#include <string>

#include "backends/robust/maximum_clique.h"
#include "core/error.h"

namespace hamal::flag {

std::vector<std::pair<int, int>> PairwiseConsistency::edges(
    const std::vector<Point2>& points, const std::vector<Eigen::Matrix2d>& covariances) const {
  if (!covariances.empty() && covariances.size() != points.size())
    throw Error("pairwise consistency: " + std::to_string(covariances.size()) +
                " covariances for " + std::to_string(points.size()) + " points");
  const bool scaled = sigmas_ > 0 && !covariances.empty();
  std::vector<std::pair<int, int>> out;
  const double t2 = threshold_ * threshold_;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      const Eigen::Vector2d d = points[i] - points[j];
      bool consistent = d.squaredNorm() <= t2;
      if (!consistent && scaled) {
        const Eigen::Matrix2d S = sigmas_ * sigmas_ * (covariances[i] + covariances[j]) +
                                  t2 * Eigen::Matrix2d::Identity();
        consistent = d.dot(S.inverse() * d) <= 1.0;
      }
      if (consistent) out.emplace_back(static_cast<int>(i), static_cast<int>(j));
    }
  return out;
}

std::vector<bool> PairwiseConsistency::check(
    const std::vector<Point2>& points, const std::vector<bool>& preferred,
    const std::vector<Eigen::Matrix2d>& covariances) const {
  const auto e = edges(points, covariances);
  return max_clique_ ? largestClique(e, points.size(), preferred) : linkCount(e, points.size());
}

std::vector<bool> PairwiseConsistency::linkCount(const std::vector<std::pair<int, int>>& edges,
                                                 std::size_t n) const {
  std::vector<int> links(n, 0);
  for (const auto& [i, j] : edges) {
    ++links[i];
    ++links[j];
  }
  std::vector<bool> accepted(n);
  for (std::size_t i = 0; i < n; ++i) accepted[i] = links[i] >= min_links_;
  return accepted;
}

std::vector<bool> PairwiseConsistency::largestClique(const std::vector<std::pair<int, int>>& edges,
                                                     std::size_t n,
                                                     const std::vector<bool>& preferred) const {
  std::vector<bool> accepted(n, false);
  if (n == 0) return accepted;
  robust::ConsistencyGraph graph;
  graph.vertices = static_cast<int>(n);
  graph.edges = edges;
  const std::vector<int>* best = nullptr;
  int best_preferred = -1;
  const auto cliques = robust::largestCliques(graph);
  for (const auto& clique : cliques) {
    int count = 0;
    for (int v : clique)
      if (static_cast<std::size_t>(v) < preferred.size() && preferred[v]) ++count;
    if (count > best_preferred) {
      best_preferred = count;
      best = &clique;
    }
  }
  if (best && static_cast<int>(best->size()) >= min_links_ + 1)
    for (int v : *best) accepted[static_cast<std::size_t>(v)] = true;
  return accepted;
}

}  // namespace hamal::flag
