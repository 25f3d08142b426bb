// Min-heap based ordering (thesis sec. 3.4.3, Alg. 3.2, eq. 3.20); see the
// header for the choices made where the thesis leaves room.
#include "backends/aprilsam/min_heap_ordering.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <string>
#include <utility>

#include "core/error.h"

namespace hamal::aprilsam {
namespace {

// The lists of a node that no longer needs them: emptied, their buffers
// kept for the workspace's next call.
void release(std::vector<int>& list) { list.clear(); }

// The first n lists of `lists`, empty (longer ones keep the rest).
template <typename List>
void emptyLists(std::vector<List>& lists, int n) {
  if (static_cast<int>(lists.size()) < n) lists.resize(n);
  for (int i = 0; i < n; ++i) lists[i].clear();
}

}  // namespace

// One function although it is long: the elimination loop's phases (pick,
// absorb the elements, rescore the neighbours) share a dozen arrays of the
// quotient graph and the heap's lists; split into functions they would
// pass all of them along, and the loop is the ordering's whole cost in a
// batch.
std::vector<int> scoreListOrdering(const OrderingInput& in, const std::vector<int>& ordered_last,
                                   Rescoring rescoring, OrderingWorkspace* workspace) {
  OrderingWorkspace own;
  OrderingWorkspace& ws = workspace != nullptr ? *workspace : own;
  // Quotient graph: a live node i keeps its live neighbours A_i and the
  // elements E_i it belongs to; an eliminated node p becomes the element
  // L_p (its neighbours in the elimination graph), which stands for the
  // clique that eliminating p creates without storing the clique's edges.
  symmetricAdjacency(in, &ws.var_adj);
  std::vector<std::vector<int>>& var_adj = ws.var_adj;
  const int n = static_cast<int>(in.adjacency.size());
  std::vector<char> last(n, 0);
  for (int v : ordered_last) {
    if (v < 0 || v >= n) {
      throw Error("ordering: node " + std::to_string(v) + " to order last is not in 0.." +
                  std::to_string(n - 1));
    }
    if (last[v]) throw Error("ordering: node " + std::to_string(v) + " listed last twice");
    last[v] = 1;
  }

  emptyLists(ws.elem_adj, n);
  emptyLists(ws.elem_vars, n);
  std::vector<std::vector<int>>& elem_adj = ws.elem_adj;  // E_i
  std::vector<std::vector<int>>& elem_vars =
      ws.elem_vars;  // L_e, for eliminated e not yet absorbed
  std::vector<long> elem_size(n, 0);
  std::vector<char> eliminated(n, 0), absorbed(n, 0);
  std::vector<long> degree(n);  // the score of eq. 3.20's second case
  for (int i = 0; i < n; ++i) degree[i] = static_cast<long>(var_adj[i].size());
  std::vector<long> w(n, 0), w_stamp(n, -1), in_lp(n, -1);
  long alive = n;
  long step = 0;
  std::vector<int> lp;  // L_p of the node eliminated last

  // Eliminates p and brings the approximate degree of every node of L_p up
  // to date (AMD: min of the previous bound grown by |L_p|, and |A_i| +
  // |L_p \ i| + sum over i's other elements of |L_e \ L_p|).
  auto eliminate = [&](int p) {
    ++step;
    eliminated[p] = 1;
    --alive;
    lp.clear();
    in_lp[p] = step;
    for (int j : var_adj[p]) {
      if (!eliminated[j] && in_lp[j] != step) {
        in_lp[j] = step;
        lp.push_back(j);
      }
    }
    for (int e : elem_adj[p]) {
      if (absorbed[e]) continue;
      for (int j : elem_vars[e]) {
        if (!eliminated[j] && in_lp[j] != step) {
          in_lp[j] = step;
          lp.push_back(j);
        }
      }
      absorbed[e] = 1;  // L_e is inside L_p + {p} now
      release(elem_vars[e]);
    }
    release(var_adj[p]);
    release(elem_adj[p]);

    // w(e) = |L_e \ L_p| for every element touching L_p.
    for (int i : lp) {
      for (int e : elem_adj[i]) {
        if (absorbed[e]) continue;
        if (w_stamp[e] != step) {
          w_stamp[e] = step;
          w[e] = elem_size[e];
        }
        --w[e];
      }
    }
    const long lp_size = static_cast<long>(lp.size());
    for (int i : lp) {
      long external = 0;
      std::vector<int>& elems = elem_adj[i];
      std::size_t k = 0;
      for (int e : elems) {
        if (absorbed[e]) continue;
        if (w[e] == 0) {  // aggressive absorption: L_e is inside L_p
          absorbed[e] = 1;
          release(elem_vars[e]);
          continue;
        }
        external += w[e];
        elems[k++] = e;
      }
      elems.resize(k);
      elems.push_back(p);
      // Edges to nodes of L_p are now implied by the element p.
      std::vector<int>& vars = var_adj[i];
      k = 0;
      for (int j : vars) {
        if (!eliminated[j] && in_lp[j] != step) vars[k++] = j;
      }
      vars.resize(k);
      degree[i] = std::min({alive - 1, degree[i] + lp_size - 1,
                            static_cast<long>(vars.size()) + lp_size - 1 + external});
    }
    elem_vars[p] = lp;
    elem_size[p] = lp_size;
  };

  // The min-heap of score lists (Alg. 3.2 lines 1-2): lists[s] holds the
  // nodes filed with score s; an entry is live while its stamp is the
  // node's current one, so re-filing a node never searches a list.
  emptyLists(ws.lists, std::max(n, 1));
  std::vector<std::vector<std::pair<int, long>>>& lists = ws.lists;
  std::vector<long> stamp(n, 0);
  std::vector<char> in_heap(std::max(n, 1), 0);
  std::priority_queue<long, std::vector<long>, std::greater<long>> heap;
  auto file = [&](int v) {
    const long key = degree[v];
    lists[key].emplace_back(v, ++stamp[v]);
    if (!in_heap[key]) {
      in_heap[key] = 1;
      heap.push(key);
    }
  };
  for (int v = 0; v < n; ++v) {
    if (!last[v]) file(v);
  }

  std::vector<int> order;
  order.reserve(n);
  std::vector<std::pair<int, long>> best;
  while (!heap.empty()) {  // Alg. 3.2 line 3
    const long min_score = heap.top();
    heap.pop();
    in_heap[min_score] = 0;
    best.clear();  // the list gets best's emptied buffer instead of a free and a malloc
    best.swap(lists[min_score]);
    for (std::size_t idx = 0; idx < best.size(); ++idx) {  // line 4; best grows in line 10
      const int nd = best[idx].first;
      if (eliminated[nd] || best[idx].second != stamp[nd]) continue;
      if (degree[nd] > min_score) {  // line 14
        file(nd);
        continue;
      }
      eliminate(nd);  // lines 6-7
      order.push_back(nd);
      if (rescoring != Rescoring::kNeighbours) continue;
      for (int nnd : lp) {  // lines 8-12
        if (last[nnd]) continue;
        if (degree[nnd] <= min_score) {
          best.emplace_back(nnd, ++stamp[nnd]);
        } else {
          file(nnd);
        }
      }
    }
  }
  order.insert(order.end(), ordered_last.begin(), ordered_last.end());
  return order;
}

std::vector<int> minHeapOrdering(const OrderingInput& in, double loop_closure_radius,
                                 OrderingWorkspace* workspace) {
  if (!(loop_closure_radius >= 0)) {
    throw Error("min-heap ordering: loop-closure radius R_T=" +
                std::to_string(loop_closure_radius) + " must be >= 0");
  }
  const int n = static_cast<int>(in.adjacency.size());
  std::vector<int> last;
  if (in.newest >= 0) {
    if (in.newest >= n) {
      throw Error("ordering: newest node " + std::to_string(in.newest) + " is not in 0.." +
                  std::to_string(n - 1));
    }
    if (static_cast<int>(in.positions.size()) != n) {
      throw Error("min-heap ordering: " + std::to_string(in.positions.size()) + " positions for " +
                  std::to_string(n) + " nodes");
    }
    // eq. 3.20's first case: score N + 1/r, so increasing score is
    // decreasing r; the newest (r = 0) goes last of all.
    const Eigen::Vector2d centre = in.positions[in.newest];
    std::vector<std::pair<double, int>> near;
    for (int i = 0; i < n; ++i) {
      if (i == in.newest) continue;
      const double r = (in.positions[i] - centre).norm();
      if (r < loop_closure_radius) near.emplace_back(r, i);
    }
    std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    last.reserve(near.size() + 1);
    for (const auto& entry : near) last.push_back(entry.second);
    last.push_back(in.newest);
  }
  return scoreListOrdering(in, last, Rescoring::kNeighbours, workspace);
}

}  // namespace hamal::aprilsam
