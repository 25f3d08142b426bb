// MaximumClique: the largest set of pairwise-consistent measurements, the
// maximum clique of a consistency graph, found by igraph (Csardi & Nepusz;
// Debian's libigraph-dev), never by a search of hamal's own. Pairwise
// Consistency Maximization (Mangelson, Dominic, Eustice, Vasudevan, ICRA
// 2018) accepts such a clique of loop closures; FLAG's landmark check (thesis
// sec. 4.3.3.1) accepts one of landmark measurements.
//
// igraph's default error handler aborts the process; here every igraph
// failure becomes a hamal::Error, and the handlers igraph had are restored
// when a call returns.
//
// Maximum clique is NP-hard, and igraph's searches report nothing for
// minutes on dense graphs of thousands of vertices (a consistency graph of
// loop closures over long odometry is almost complete). maximumClique() is
// exact: igraph_clique_number gives the size, igraph_cliques_callback
// (Cliquer) the first cliques of that size. With a time budget the search
// runs in a child process that is killed when the budget runs out (igraph
// 0.10.2 cannot be interrupted safely); then the result is empty and marked
// exact = false, and the caller decides what to do instead.
#pragma once

#include <utility>
#include <vector>

namespace hamal::robust {

// An undirected graph on vertices 0 .. vertices-1; each edge once, i != j.
struct ConsistencyGraph {
  int vertices = 0;
  std::vector<std::pair<int, int>> edges;
};

// Every largest clique, each sorted (igraph_largest_cliques). For small
// graphs: their number can grow exponentially with the graph.
std::vector<std::vector<int>> largestCliques(const ConsistencyGraph& graph);

struct CliqueResult {
  std::vector<int> members;  // sorted vertex ids; empty when the budget ran out
  bool exact = true;         // a maximum clique (false: the budget ran out)
  double seconds = 0;        // wall time inside igraph
};

// One maximum clique. Among the first `ties` maximum cliques igraph lists,
// the one holding the most `preferred` vertices wins (then the first): what
// was accepted before stays accepted when it can. budget_seconds <= 0: no
// budget, always exact. Throws hamal::Error on an edge that is not between
// two vertices, or when igraph fails.
CliqueResult maximumClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred = {},
                           double budget_seconds = 0, int ties = 64);

}  // namespace hamal::robust
