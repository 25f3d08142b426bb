// TopReelimination: see top_reelimination.h (iSAM2's re-elimination of the
// top in AprilSAM's R; min-heap ordering, thesis Alg. 3.2).
#include "backends/aprilsam/top_reelimination.h"

#include <cmath>

#include "backends/aprilsam/ordering_input.h"

namespace hamal::aprilsam {

bool TopReelimination::run(const std::string& reason, PhaseClock* clock, UpdateResult* result) {
  if (g_.modes.any || g_.damped || g_.broken) return false;
  const int m = g_.chol.size();
  const std::vector<int> top = chooseTop();
  const int nt = static_cast<int>(top.size());
  if (nt == 0) return false;
  const long relinearized = relinearizeFree(top);
  clock->lap(&result->time.other);

  std::vector<int> rank;
  const std::vector<int> order = orderTop(top, &rank);
  clock->lap(&result->time.order);

  if (!linearizeTop(rank, m - nt, result)) return false;
  clock->lap(&result->time.linearize);

  std::vector<int> new_pos;
  const IncrementalCholesky::Outcome out = g_.chol.reorderTop(top, order, g_.neq, &new_pos);
  clock->lap(&result->time.factor);
  if (!out.ok) return false;  // the batch that follows rebuilds R
  const std::vector<int> old_var_at = g_.var_at;
  for (int p = 0; p < m; ++p) {
    g_.var_at[new_pos[p]] = old_var_at[p];
    g_.pos_of[old_var_at[p]] = new_pos[p];
  }
  // Every row is solved, as after a batch: the partial solves' tolerance
  // (backsolve_tolerance) has let dx drift by up to that much per row since the
  // last full solve, and with few batches nothing else would correct it
  // (on city10000 the drift alone leaves the final chi2 well outside 1e-4
  // of the optimum). The kept rows' dx move to their new positions first,
  // so that the changed set is what the re-elimination changed.
  g_.solve.permute(new_pos);
  g_.solve.solve(g_.chol, true, 0.0);
  g_.applyChangedDx();
  if (!g_.estimateIsFinite(result)) {
    g_.broken = true;
    return true;
  }
  clock->lap(&result->time.solve);
  g_.factors_at_top = g_.factors.size();
  // The time criterion weighs the increments against a batch of R as it is
  // now; the last full batch's R may be far smaller.
  if (options_.policy.cost == UpdatePolicyOptions::Cost::kDeterministic)
    g_.last_batch_cost = g_.chol.totalFlops();
  result->kind = UpdateKind::kIncremental;
  result->reason = reason + "; top re-eliminated: " + std::to_string(nt) + " of " +
                   std::to_string(m) + " rows, " + std::to_string(relinearized) +
                   " variables relinearised";
  result->columns_recomputed += out.columns_recomputed;
  result->variables_relinearized = relinearized;
  return true;
}

std::vector<int> TopReelimination::chooseTop() const {
  const int n = static_cast<int>(g_.keys.size());
  std::vector<int> path, relin;
  for (std::size_t f = g_.factors_at_top; f < g_.factors.size(); ++f)
    for (int k = g_.factor_begin[f]; k < g_.factor_begin[f + 1]; ++k)
      if (g_.pos_of[g_.factor_vars[k]] >= 0) path.push_back(g_.pos_of[g_.factor_vars[k]]);
  // The variables due (a full batch moves every variable, so AprilSAM's
  // batches do not need the rule).
  for (int v = 0; v < n; ++v)
    if (due(v)) relin.push_back(g_.pos_of[v]);
  std::vector<int> top = g_.chol.topOf(path, relin);
  if (static_cast<double>(top.size()) > options_.top_share * g_.chol.size()) top.clear();
  return top;
}

bool TopReelimination::due(int v) const {
  const double r = options_.top_relinearize * options_.policy.delta_t;
  return g_.pos_of[v] >= 0 && (g_.moved[v] || g_.dx_sq_of[v] >= r * r);
}

long TopReelimination::relinearizeFree(const std::vector<int>& top) {
  // The factors on the top; one that also reaches a kept row holds the
  // top variables it touches at their linearisation points (the kept row
  // has it linearised there).
  const int nt = static_cast<int>(top.size());
  local_.assign(g_.keys.size(), -1);
  for (int k = 0; k < nt; ++k) local_[g_.var_at[top[k]]] = k;
  ++g_.stamp;
  fs_.clear();
  std::vector<char> pinned(nt, 0);
  for (int p : top) {
    for (int f : g_.factors_of_var[g_.var_at[p]]) {
      if (g_.factor_stamp[f] == g_.stamp) continue;
      g_.factor_stamp[f] = g_.stamp;
      fs_.push_back(f);
      bool straddles = false;
      for (int k = g_.factor_begin[f]; k < g_.factor_begin[f + 1]; ++k) {
        const int u = g_.factor_vars[k];
        straddles |= g_.pos_of[u] >= 0 && local_[u] < 0;
      }
      if (!straddles) continue;
      for (int k = g_.factor_begin[f]; k < g_.factor_begin[f + 1]; ++k)
        if (local_[g_.factor_vars[k]] >= 0) pinned[local_[g_.factor_vars[k]]] = 1;
    }
  }
  long relinearized = 0;
  for (int k = 0; k < nt; ++k) {
    if (pinned[k]) continue;
    g_.moveLinearizationPoint(g_.var_at[top[k]]);
    ++relinearized;
  }
  return relinearized;
}

std::vector<int> TopReelimination::orderTop(const std::vector<int>& top, std::vector<int>* rank) {
  // The top's graph: its factors, and the separator of each kept subtree
  // hanging from the top as a clique (the marginal it leaves there). A
  // row's structure holds its children's but for the parent itself, so the
  // subtree's root row (its parent in the top) has the whole separator.
  const int nt = static_cast<int>(top.size());
  const int m = g_.chol.size();
  OrderingInput in;
  in.adjacency.assign(nt, {});
  in.positions.resize(nt);
  for (int k = 0; k < nt; ++k) in.positions[k] = g_.orderingPosition(g_.var_at[top[k]]);
  in.newest = g_.newest_pose >= 0 ? local_[g_.newest_pose] : -1;
  for (int f : fs_)
    for (int i = g_.factor_begin[f]; i < g_.factor_begin[f + 1]; ++i)
      for (int j = i + 1; j < g_.factor_begin[f + 1]; ++j) {
        const int a = local_[g_.factor_vars[i]], b = local_[g_.factor_vars[j]];
        if (a >= 0 && b >= 0) in.adjacency[a].push_back(b);
      }
  std::vector<int> sep;
  for (int p = 0; p < m; ++p) {
    const int parent = g_.chol.parent(p);
    if (local_[g_.var_at[p]] >= 0 || parent < 0 || local_[g_.var_at[parent]] < 0) continue;
    const IncrementalCholesky::Row r = g_.chol.row(p);
    sep.clear();
    for (std::size_t k = 1; k < r.cols.size(); ++k) {
      const int l = local_[g_.var_at[r.cols[k]]];
      if (l >= 0) sep.push_back(l);
    }
    for (std::size_t i = 0; i < sep.size(); ++i)
      for (std::size_t j = i + 1; j < sep.size(); ++j) in.adjacency[sep[i]].push_back(sep[j]);
  }
  const std::vector<int> local_order =
      minHeapOrdering(in, options_.loop_closure_radius, &workspace_);
  std::vector<int> order(nt);
  rank->resize(nt);
  for (int k = 0; k < nt; ++k) {
    order[k] = top[local_order[k]];
    (*rank)[local_order[k]] = k;
  }
  return order;
}

bool TopReelimination::linearizeTop(const std::vector<int>& rank, int kept, UpdateResult* result) {
  // H on the top at its new positions (after the kept rows), the kept
  // variables at none (their blocks dropped, as a fixed variable's).
  const int m = g_.chol.size();
  for (int f : fs_)
    for (int k = g_.factor_begin[f]; k < g_.factor_begin[f + 1]; ++k) {
      const int u = g_.factor_vars[k];
      g_.pos_of[u] = local_[u] >= 0 ? kept + rank[local_[u]] : -1;
    }
  g_.neq.clear(m);
  double cost = 0;
  bool ok = true;
  for (int f : fs_) {
    if (!(ok = g_.linearizeFactor(f, 1.0, false, result))) break;
    cost += g_.scratch.cost;
  }
  for (int p = 0; p < m; ++p) g_.pos_of[g_.var_at[p]] = p;
  if (!ok || !std::isfinite(cost)) {
    result->status = Status();
    return false;
  }
  return true;
}

}  // namespace hamal::aprilsam
