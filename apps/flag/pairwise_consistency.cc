// The pairwise consistency check (pairwise_consistency.h; thesis sec. 4.3.3.1).
#include "apps/flag/pairwise_consistency.h"

#include <igraph.h>

#include "core/error.h"

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

namespace {
// igraph's default handler aborts; hamal turns a failure into an Error.
void igraphCheck(igraph_error_t code, const char* what) {
  if (code != IGRAPH_SUCCESS)
    throw Error(std::string("pairwise consistency: igraph failed in ") + what + ": " +
                igraph_strerror(code));
}
}  // namespace

std::vector<bool> PairwiseConsistency::largestClique(const std::vector<Point2>& points,
                                                     const std::vector<bool>& preferred) const {
  std::vector<bool> accepted(points.size(), false);
  if (points.empty()) return accepted;
  igraph_set_error_handler(igraph_error_handler_ignore);
  const auto e = edges(points);
  igraph_vector_int_t edge_list;
  igraphCheck(igraph_vector_int_init(&edge_list, static_cast<igraph_integer_t>(2 * e.size())),
              "vector_int_init");
  for (std::size_t k = 0; k < e.size(); ++k) {
    VECTOR(edge_list)[2 * k] = e[k].first;
    VECTOR(edge_list)[2 * k + 1] = e[k].second;
  }
  igraph_t graph;
  igraph_error_t code = igraph_create(
      &graph, &edge_list, static_cast<igraph_integer_t>(points.size()), IGRAPH_UNDIRECTED);
  igraph_vector_int_destroy(&edge_list);
  igraphCheck(code, "create");
  igraph_vector_int_list_t cliques;
  code = igraph_vector_int_list_init(&cliques, 0);
  if (code != IGRAPH_SUCCESS) {
    igraph_destroy(&graph);
    igraphCheck(code, "vector_int_list_init");
  }
  code = igraph_largest_cliques(&graph, &cliques);
  if (code == IGRAPH_SUCCESS) {
    const igraph_integer_t n = igraph_vector_int_list_size(&cliques);
    igraph_integer_t best = -1;
    int best_preferred = -1;
    for (igraph_integer_t c = 0; c < n; ++c) {
      const igraph_vector_int_t* members = igraph_vector_int_list_get_ptr(&cliques, c);
      int count = 0;
      for (igraph_integer_t k = 0; k < igraph_vector_int_size(members); ++k) {
        const auto v = static_cast<std::size_t>(VECTOR(*members)[k]);
        if (v < preferred.size() && preferred[v]) ++count;
      }
      if (count > best_preferred) {
        best_preferred = count;
        best = c;
      }
    }
    if (best >= 0) {
      const igraph_vector_int_t* members = igraph_vector_int_list_get_ptr(&cliques, best);
      if (igraph_vector_int_size(members) >= min_links_ + 1)
        for (igraph_integer_t k = 0; k < igraph_vector_int_size(members); ++k)
          accepted[static_cast<std::size_t>(VECTOR(*members)[k])] = true;
    }
  }
  igraph_vector_int_list_destroy(&cliques);
  igraph_destroy(&graph);
  igraphCheck(code, "largest_cliques");
  return accepted;
}

}  // namespace hamal::flag
