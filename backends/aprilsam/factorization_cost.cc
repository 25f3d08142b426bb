// Deterministic factorisation cost for the update policy (thesis sec. 3.4.4);
// see the header for why flops stand in for time.
#include "backends/aprilsam/factorization_cost.h"

#include <string>

#include "core/error.h"

namespace hamal::aprilsam {

double choleskyFlops(const std::vector<long>& column_counts) {
  double flops = 0;
  for (long c : column_counts) flops += static_cast<double>(c) * static_cast<double>(c);
  return flops;
}

std::vector<long> choleskyColumnCounts(const std::vector<std::vector<int>>& adjacency,
                                       const std::vector<int>& order) {
  const int n = static_cast<int>(adjacency.size());
  if (static_cast<int>(order.size()) != n) {
    throw Error("cholesky column counts: order has " + std::to_string(order.size()) +
                " entries for " + std::to_string(n) + " nodes");
  }
  std::vector<int> position(n, -1);
  for (int k = 0; k < n; ++k) {
    const int node = order[k];
    if (node < 0 || node >= n || position[node] != -1) {
      throw Error("cholesky column counts: order is not a permutation of 0.." +
                  std::to_string(n - 1) + " (entry " + std::to_string(k) + " = " +
                  std::to_string(node) + ")");
    }
    position[node] = k;
  }
  // Row k of the permuted lower triangle: the earlier-eliminated neighbours.
  std::vector<std::vector<int>> row(n);
  for (int u = 0; u < n; ++u) {
    for (int v : adjacency[u]) {
      if (v < 0 || v >= n) {
        throw Error("cholesky column counts: node " + std::to_string(u) + " has neighbour " +
                    std::to_string(v) + " outside 0.." + std::to_string(n - 1));
      }
      const int a = position[u], b = position[v];
      if (a == b) continue;
      if (a > b) {
        row[a].push_back(b);
      } else {
        row[b].push_back(a);
      }
    }
  }
  // Elimination tree (Liu's algorithm with path compression), then each
  // row's pattern is the row subtree reached from its entries: every node
  // visited is one nonzero L(k, i) of column i.
  std::vector<int> parent(n, -1), ancestor(n, -1), mark(n, -1);
  std::vector<long> counts(n, 1);  // the diagonal
  for (int k = 0; k < n; ++k) {
    for (int i : row[k]) {
      while (i != -1 && i < k) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) {
          parent[i] = k;
          break;
        }
        i = next;
      }
    }
    mark[k] = k;
    for (int i : row[k]) {
      while (mark[i] != k) {
        mark[i] = k;
        ++counts[i];
        i = parent[i];
      }
    }
  }
  return counts;
}

}  // namespace hamal::aprilsam
