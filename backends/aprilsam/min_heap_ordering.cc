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

// The elimination graph as a quotient graph (AMD's: Amestoy, Davis, Duff
// 1996): a live node i keeps its live neighbours A_i and the elements E_i
// it belongs to; an eliminated node p becomes the element L_p (its
// neighbours in the elimination graph), which stands for the clique that
// eliminating p creates without storing the clique's edges. degree(i) is
// AMD's approximate degree, the score of eq. 3.20's second case.
class QuotientGraph {
 public:
  // The graph of `in`, nothing eliminated, its lists in ws's buffers.
  QuotientGraph(const OrderingInput& in, OrderingWorkspace& ws)
      : var_adj_(ws.var_adj), elem_adj_(ws.elem_adj), elem_vars_(ws.elem_vars) {
    symmetricAdjacency(in, &var_adj_);
    const int n = static_cast<int>(in.adjacency.size());
    emptyLists(elem_adj_, n);
    emptyLists(elem_vars_, n);
    elem_size_.assign(n, 0);
    eliminated_.assign(n, 0);
    absorbed_.assign(n, 0);
    degree_.resize(n);
    for (int i = 0; i < n; ++i) degree_[i] = static_cast<long>(var_adj_[i].size());
    w_.assign(n, 0);
    w_stamp_.assign(n, -1);
    in_lp_.assign(n, -1);
    alive_ = n;
  }
  long degree(int i) const { return degree_[i]; }
  bool eliminated(int i) const { return eliminated_[i]; }

  // Eliminates p and brings the approximate degree of every node of L_p up
  // to date; returns L_p (valid until the next elimination).
  const std::vector<int>& eliminate(int p) {
    ++step_;
    eliminated_[p] = 1;
    --alive_;
    formElement(p);
    updateDegrees(p);
    return lp_;
  }

 private:
  // L_p = A_p and the nodes of p's elements, which it absorbs.
  void formElement(int p) {
    lp_.clear();
    in_lp_[p] = step_;
    for (int j : var_adj_[p]) {
      if (!eliminated_[j] && in_lp_[j] != step_) {
        in_lp_[j] = step_;
        lp_.push_back(j);
      }
    }
    for (int e : elem_adj_[p]) {
      if (absorbed_[e]) continue;
      for (int j : elem_vars_[e]) {
        if (!eliminated_[j] && in_lp_[j] != step_) {
          in_lp_[j] = step_;
          lp_.push_back(j);
        }
      }
      absorbed_[e] = 1;  // L_e is inside L_p + {p} now
      release(elem_vars_[e]);
    }
    release(var_adj_[p]);
    release(elem_adj_[p]);
  }

  // AMD's bound for each node i of L_p: min of the previous bound grown by
  // |L_p|, and |A_i| + |L_p \ i| + sum over i's other elements of
  // |L_e \ L_p|; i's lists lose what the element p now implies.
  void updateDegrees(int p) {
    // w(e) = |L_e \ L_p| for every element touching L_p.
    for (int i : lp_) {
      for (int e : elem_adj_[i]) {
        if (absorbed_[e]) continue;
        if (w_stamp_[e] != step_) {
          w_stamp_[e] = step_;
          w_[e] = elem_size_[e];
        }
        --w_[e];
      }
    }
    const long lp_size = static_cast<long>(lp_.size());
    for (int i : lp_) {
      long external = 0;
      std::vector<int>& elems = elem_adj_[i];
      std::size_t k = 0;
      for (int e : elems) {
        if (absorbed_[e]) continue;
        if (w_[e] == 0) {  // aggressive absorption: L_e is inside L_p
          absorbed_[e] = 1;
          release(elem_vars_[e]);
          continue;
        }
        external += w_[e];
        elems[k++] = e;
      }
      elems.resize(k);
      elems.push_back(p);
      // Edges to nodes of L_p are now implied by the element p.
      std::vector<int>& vars = var_adj_[i];
      k = 0;
      for (int j : vars) {
        if (!eliminated_[j] && in_lp_[j] != step_) vars[k++] = j;
      }
      vars.resize(k);
      degree_[i] = std::min({alive_ - 1, degree_[i] + lp_size - 1,
                             static_cast<long>(vars.size()) + lp_size - 1 + external});
    }
    elem_vars_[p] = lp_;
    elem_size_[p] = lp_size;
  }

  std::vector<std::vector<int>>& var_adj_;    // A_i
  std::vector<std::vector<int>>& elem_adj_;   // E_i
  std::vector<std::vector<int>>& elem_vars_;  // L_e, for eliminated e not yet absorbed
  std::vector<long> elem_size_;
  std::vector<char> eliminated_, absorbed_;
  std::vector<long> degree_;
  std::vector<long> w_, w_stamp_, in_lp_;
  long alive_ = 0;
  long step_ = 0;
  std::vector<int> lp_;  // L_p of the node eliminated last
};

// The min-heap of score lists (Alg. 3.2 lines 1-2): list s holds the nodes
// filed with score s; an entry is live while its stamp is the node's
// current one, so re-filing a node never searches a list.
class ScoreLists {
 public:
  using Entry = std::pair<int, long>;  // node, stamp
  ScoreLists(int n, OrderingWorkspace& ws) : lists_(ws.lists) {
    emptyLists(lists_, std::max(n, 1));
    stamp_.assign(n, 0);
    in_heap_.assign(std::max(n, 1), 0);
  }
  // Files v under `score`, making its earlier entries stale.
  void file(int v, long score) {
    lists_[score].push_back(restamp(v));
    if (!in_heap_[score]) {
      in_heap_[score] = 1;
      heap_.push(score);
    }
  }
  // A new entry for v, making its earlier entries stale.
  Entry restamp(int v) { return Entry(v, ++stamp_[v]); }
  bool live(const Entry& e) const { return e.second == stamp_[e.first]; }
  bool empty() const { return heap_.empty(); }
  // Takes the list of the smallest score out into `best` (which gives the
  // list its emptied buffer instead of a free and a malloc).
  long popMin(std::vector<Entry>* best) {
    const long min_score = heap_.top();
    heap_.pop();
    in_heap_[min_score] = 0;
    best->clear();
    best->swap(lists_[min_score]);
    return min_score;
  }

 private:
  std::vector<std::vector<Entry>>& lists_;
  std::vector<long> stamp_;
  std::vector<char> in_heap_;
  std::priority_queue<long, std::vector<long>, std::greater<long>> heap_;
};

// 1 for the nodes of `ordered_last`, 0 elsewhere; throws on a node listed
// twice or outside 0..n-1.
std::vector<char> markOrderedLast(const std::vector<int>& ordered_last, int n) {
  std::vector<char> last(n, 0);
  for (int v : ordered_last) {
    if (v < 0 || v >= n) {
      throw Error("ordering: node " + std::to_string(v) + " to order last is not in 0.." +
                  std::to_string(n - 1));
    }
    if (last[v]) throw Error("ordering: node " + std::to_string(v) + " listed last twice");
    last[v] = 1;
  }
  return last;
}

}  // namespace

std::vector<int> scoreListOrdering(const OrderingInput& in, const std::vector<int>& ordered_last,
                                   Rescoring rescoring, OrderingWorkspace* workspace) {
  OrderingWorkspace own;
  OrderingWorkspace& ws = workspace != nullptr ? *workspace : own;
  QuotientGraph graph(in, ws);
  const int n = static_cast<int>(in.adjacency.size());
  const std::vector<char> last = markOrderedLast(ordered_last, n);
  ScoreLists scores(n, ws);
  for (int v = 0; v < n; ++v) {
    if (!last[v]) scores.file(v, graph.degree(v));
  }

  std::vector<int> order;
  order.reserve(n);
  std::vector<ScoreLists::Entry> best;
  while (!scores.empty()) {  // Alg. 3.2 line 3
    const long min_score = scores.popMin(&best);
    for (std::size_t idx = 0; idx < best.size(); ++idx) {  // line 4; best grows in line 10
      const int nd = best[idx].first;
      if (graph.eliminated(nd) || !scores.live(best[idx])) continue;
      if (graph.degree(nd) > min_score) {  // line 14
        scores.file(nd, graph.degree(nd));
        continue;
      }
      const std::vector<int>& lp = graph.eliminate(nd);  // lines 6-7
      order.push_back(nd);
      if (rescoring != Rescoring::kNeighbours) continue;
      for (int nnd : lp) {  // lines 8-12
        if (last[nnd]) continue;
        if (graph.degree(nnd) <= min_score) {
          best.push_back(scores.restamp(nnd));
        } else {
          scores.file(nnd, graph.degree(nnd));
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
