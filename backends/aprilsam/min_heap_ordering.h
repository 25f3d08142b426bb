// Min-heap based ordering (thesis sec. 3.4.3, Alg. 3.2, score of eq. 3.20).
//
// A batch update orders the nodes that the next loop closures may touch at
// the end of the factor R, so that an incremental update (eq. 3.14) only
// recomputes a small trailing block. eq. 3.20 scores a node N + 1/r when it
// lies within r < R_T of the newest pose, and by its connection degree n
// otherwise; Alg. 3.2 eliminates, from a min-heap of score lists, the node
// of smallest score, and re-scores and re-files the neighbours of each node
// it eliminates.
//
// Choices this implementation makes, where the thesis leaves room:
// - "Connection degree" is the degree in the ELIMINATION graph (eliminating
//   a node joins its neighbours), as in minimum-degree orderings: the
//   neighbours' re-scoring after a removal only matters when the removal can
//   change their degree both ways, and a degree that ignored fill would make
//   a peeling order with far more fill on SLAM graphs (loops of poses).
// - To bound the work of fill (a 10^6-node graph has separators of ~10^3
//   nodes, whose explicit cliques cost 10^6 edges each), the elimination
//   graph is kept as a quotient graph (eliminated nodes become "elements",
//   element absorption, aggressive absorption), and the degree is AMD's
//   approximate degree (Amestoy, Davis, Duff 1996): an upper bound on the
//   true degree, usually equal to it. No supervariables or mass elimination,
//   for simplicity (see the cost below).
// - The nodes within R_T (scores > N, fixed) therefore come last, in
//   increasing score: farthest first, nearest last; the newest pose (r = 0,
//   score +inf) is always last, even for R_T = 0, and nodes at equal
//   distance keep their id order. Their degree does not matter.
// - Every node within R_T is ordered by distance alone, so R_T must stay
//   small against the map: with all nodes inside (e.g. all positions equal)
//   the order degenerates to the natural one and fills like it.
// - Ties among equal degrees are broken by the order nodes were filed
//   (initially by id), so the ordering is deterministic.
//
// Cost: comparable to AMD's, with fill close to AMD's, on the public
// datasets' node graphs; several times AMD's on 10^6-node graphs, where
// after many eliminations nodes become indistinguishable and AMD's
// supervariables pay off (figures: docs/RECORD.md).
#pragma once

#include <utility>
#include <vector>

#include "backends/aprilsam/ordering_input.h"

namespace hamal::aprilsam {

// The lists of scoreListOrdering's quotient graph and score heap, for a
// caller that orders many graphs (AprilSAM orders at every batch and every
// re-eliminated top): kept between calls, their buffers are reused where a
// call would allocate and free a few lists per node. It holds nothing
// between calls that changes an order; one workspace serves one call at a
// time.
struct OrderingWorkspace {
  std::vector<std::vector<int>> var_adj, elem_adj, elem_vars;
  std::vector<std::vector<std::pair<int, long>>> lists;
};

// Elimination order (order[k] = node eliminated k-th). Throws hamal::Error
// on a bad input (see symmetricAdjacency), a negative or NaN radius, or
// positions.size() != n when in.newest >= 0.
std::vector<int> minHeapOrdering(const OrderingInput& in, double loop_closure_radius,
                                 OrderingWorkspace* workspace = nullptr);

// How Alg. 3.2 keeps the score lists current: the difference the thesis
// draws between its ordering and BHAMD.
enum class Rescoring {
  // Alg. 3.2 lines 8-12: after a removal, each neighbour is re-scored and
  // moved to the list of its new score (or back into the current list).
  kNeighbours,
  // BHAMD: scores are kept current but a node stays in the list it was
  // filed in until that list is extracted; then it is eliminated if its
  // score is no larger than the list's, re-filed otherwise. A node whose
  // degree fell stays behind in a higher list.
  kOnExtraction,
};

// The engine of both orderings: eliminates every node not in `ordered_last`
// by smallest (approximate elimination-graph) degree from the min-heap of
// score lists, then appends `ordered_last` in the order given (those nodes
// have fixed scores larger than any degree).
std::vector<int> scoreListOrdering(const OrderingInput& in, const std::vector<int>& ordered_last,
                                   Rescoring rescoring, OrderingWorkspace* workspace = nullptr);

}  // namespace hamal::aprilsam
