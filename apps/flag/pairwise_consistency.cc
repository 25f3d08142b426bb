// The pairwise consistency check (pairwise_consistency.h; thesis sec. 4.3.3.1).
#include "apps/flag/pairwise_consistency.h"

#include "backends/robust/maximum_clique.h"

namespace hamal::flag {

std::vector<std::pair<int, int>> PairwiseConsistency::edges(
    const std::vector<Point2>& points) const {
  std::vector<std::pair<int, int>> out;
  const double t2 = threshold_ * threshold_;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t j = i + 1; j < points.size(); ++j)
      if ((points[i] - points[j]).squaredNorm() <= t2)
        out.emplace_back(static_cast<int>(i), static_cast<int>(j));
  return out;
}

std::vector<bool> PairwiseConsistency::check(const std::vector<Point2>& points,
                                             const std::vector<bool>& preferred) const {
  return max_clique_ ? largestClique(points, preferred) : linkCount(points);
}

std::vector<bool> PairwiseConsistency::linkCount(const std::vector<Point2>& points) const {
  std::vector<int> links(points.size(), 0);
  for (const auto& [i, j] : edges(points)) {
    ++links[i];
    ++links[j];
  }
  std::vector<bool> accepted(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) accepted[i] = links[i] >= min_links_;
  return accepted;
}

std::vector<bool> PairwiseConsistency::largestClique(const std::vector<Point2>& points,
                                                     const std::vector<bool>& preferred) const {
  std::vector<bool> accepted(points.size(), false);
  if (points.empty()) return accepted;
  robust::ConsistencyGraph graph;
  graph.vertices = static_cast<int>(points.size());
  graph.edges = edges(points);
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
