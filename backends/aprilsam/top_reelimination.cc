// TopReelimination: see top_reelimination.h (iSAM2's re-elimination of the
// top in AprilSAM's R; min-heap ordering, thesis Alg. 3.2).
#include "backends/aprilsam/top_reelimination.h"

#include <cmath>

#include "backends/aprilsam/ordering_input.h"

namespace hamal::aprilsam {

bool TopReelimination::run(const std::string& reason, PhaseClock* clock, UpdateResult* result) {
  BatchRecord& record = g_.record();
  oversized_ = false;
  if (g_.modes().any || record.damped || record.broken) return false;
  IncrementalCholesky& chol = g_.chol();
  const int m = chol.size();
  const std::vector<int> top = chooseTop();
  const int nt = static_cast<int>(top.size());
  if (nt == 0) return false;
  if (static_cast<double>(nt) > options_.top.share * m) {
    oversized_ = true;
    return false;
  }
  const long relinearized = relinearizeFree(top);
  clock->lap(&result->time.other);

  std::vector<int> rank;
  const std::vector<int> order = orderTop(top, &rank);
  clock->lap(&result->time.order);

  if (!linearizeTop(rank, m - nt, result)) return false;
  clock->lap(&result->time.linearize);

  std::vector<int> new_pos;
  const IncrementalCholesky::Outcome out = chol.reorderTop(top, order, g_.neq(), &new_pos);
  clock->lap(&result->time.factor);
  if (!out.ok) return false;  // the batch that follows rebuilds R
  // Every row is solved, as after a batch: the partial solves' tolerance
  // (backsolve_tolerance) has let dx drift by up to that much per row since the
  // last full solve, and with few batches nothing else would correct it
  // (on city10000 the drift alone leaves the final chi2 well outside 1e-4
  // of the optimum). The kept rows' dx move to their new positions first,
  // so that the changed set is what the re-elimination changed.
  g_.permuteOrder(new_pos);
  g_.solve().solve(chol, true, 0.0);
  g_.applyChangedDx();
  if (!g_.estimateIsFinite(result)) {
    record.broken = true;
    return true;
  }
  clock->lap(&result->time.solve);
  record.factors_at_top = g_.factors().size();
  // The time criterion weighs the increments against a batch of R as it is
  // now; the last full batch's R may be far smaller.
  if (options_.policy.cost == UpdatePolicyOptions::Cost::kDeterministic)
    record.last_batch_cost = chol.totalFlops();
  result->kind = UpdateKind::kIncremental;
  result->reason = reason + "; top re-eliminated: " + std::to_string(nt) + " of " +
                   std::to_string(m) + " rows, " + std::to_string(relinearized) +
                   " variables relinearised";
  result->columns_recomputed += out.columns_recomputed;
  result->variables_relinearized = relinearized;
  return true;
}

std::vector<int> TopReelimination::chooseTop() const {
  const FactorTable& factors = g_.factors();
  const EliminationOrder& order = g_.order();
  const int n = g_.variables().size();
  std::vector<int> path, relin;
  for (std::size_t f = g_.record().factors_at_top; f < factors.size(); ++f)
    for (int v : factors.vars(f))
      if (order.posOf(v) >= 0) path.push_back(order.posOf(v));
  // The variables due (a full batch moves every variable, so AprilSAM's
  // batches do not need the rule).
  for (int v = 0; v < n; ++v)
    if (due(v)) relin.push_back(order.posOf(v));
  return g_.chol().topOf(path, relin);
}

bool TopReelimination::due(int v) const {
  const double r = options_.top.relinearize * options_.policy.delta_t;
  return g_.order().posOf(v) >= 0 && (g_.moved().moved(v) || g_.moved().dxSquared(v) >= r * r);
}

long TopReelimination::relinearizeFree(const std::vector<int>& top) {
  // The factors on the top; one that also reaches a kept row holds the
  // top variables it touches at their linearisation points (the kept row
  // has it linearised there). Not one R holds at weight 0 (a closure a
  // robust wrapper rejected): the kept row has nothing of it, and pinning
  // for it would keep a variable due from moving its point for as long as
  // the weight stays 0, while the map moves it further from the point
  // with every solve (stale Jacobians hundreds of metres off diverge).
  const FactorTable& factors = g_.factors();
  const EliminationOrder& order = g_.order();
  const int nt = static_cast<int>(top.size());
  local_.assign(g_.variables().size(), -1);
  for (int k = 0; k < nt; ++k) local_[order.varAt(top[k])] = k;
  stamps_.newPass(factors.size());
  fs_.clear();
  std::vector<char> pinned(nt, 0);
  for (int p : top) {
    for (int f : factors.factorsOf(order.varAt(p))) {
      if (!stamps_.visit(f)) continue;
      fs_.push_back(f);
      if (factors.linWeight(f) == 0) continue;
      bool straddles = false;
      for (int u : factors.vars(f)) straddles |= order.posOf(u) >= 0 && local_[u] < 0;
      if (!straddles) continue;
      for (int u : factors.vars(f))
        if (local_[u] >= 0) pinned[local_[u]] = 1;
    }
  }
  long relinearized = 0;
  for (int k = 0; k < nt; ++k) {
    if (pinned[k]) continue;
    g_.variables().moveLinearizationPoint(order.varAt(top[k]));
    ++relinearized;
  }
  return relinearized;
}

std::vector<int> TopReelimination::orderTop(const std::vector<int>& top, std::vector<int>* rank) {
  // The top's graph: its factors, and the separator of each kept subtree
  // hanging from the top as a clique (the marginal it leaves there). A
  // row's structure holds its children's but for the parent itself, so the
  // subtree's root row (its parent in the top) has the whole separator.
  const VariableTable& vars = g_.variables();
  const EliminationOrder& order = g_.order();
  const IncrementalCholesky& chol = g_.chol();
  const int nt = static_cast<int>(top.size());
  const int m = chol.size();
  OrderingInput& in = top_graph_;
  std::vector<std::vector<int>>& adjacency = in.adjacency;
  while (static_cast<int>(adjacency.size()) > nt) {
    spare_lists_.push_back(std::move(adjacency.back()));
    adjacency.pop_back();
  }
  while (static_cast<int>(adjacency.size()) < nt) {
    if (spare_lists_.empty()) {
      adjacency.emplace_back();
    } else {
      adjacency.push_back(std::move(spare_lists_.back()));
      spare_lists_.pop_back();
    }
  }
  for (std::vector<int>& list : adjacency) list.clear();
  in.positions.resize(nt);
  for (int k = 0; k < nt; ++k) in.positions[k] = vars.orderingPosition(order.varAt(top[k]));
  in.newest = vars.newestPose() >= 0 ? local_[vars.newestPose()] : -1;
  for (int f : fs_) {
    const IndexRange fv = g_.factors().vars(f);
    for (const int* i = fv.begin(); i < fv.end(); ++i)
      for (const int* j = i + 1; j < fv.end(); ++j) {
        const int a = local_[*i], b = local_[*j];
        if (a >= 0 && b >= 0) in.adjacency[a].push_back(b);
      }
  }
  std::vector<int> sep;
  for (int p = 0; p < m; ++p) {
    const int parent = chol.parent(p);
    if (local_[order.varAt(p)] >= 0 || parent < 0 || local_[order.varAt(parent)] < 0) continue;
    const IncrementalCholesky::Row r = chol.row(p);
    sep.clear();
    for (std::size_t k = 1; k < r.cols.size(); ++k) {
      const int l = local_[order.varAt(r.cols[k])];
      if (l >= 0) sep.push_back(l);
    }
    for (std::size_t i = 0; i < sep.size(); ++i)
      for (std::size_t j = i + 1; j < sep.size(); ++j) in.adjacency[sep[i]].push_back(sep[j]);
  }
  const std::vector<int> local_order =
      minHeapOrdering(in, options_.loop_closure_radius, &workspace_);
  std::vector<int> new_order(nt);
  rank->resize(nt);
  for (int k = 0; k < nt; ++k) {
    new_order[k] = top[local_order[k]];
    (*rank)[local_order[k]] = k;
  }
  return new_order;
}

bool TopReelimination::linearizeTop(const std::vector<int>& rank, int kept, UpdateResult* result) {
  // H on the top at its new positions (after the kept rows), the kept
  // variables at none (their blocks dropped, as a fixed variable's).
  positions_.resize(g_.variables().size());
  for (int f : fs_)
    for (int u : g_.factors().vars(f)) positions_[u] = local_[u] >= 0 ? kept + rank[local_[u]] : -1;
  g_.neq().clear(g_.chol().size());
  double cost = 0;
  bool ok = true;
  for (int f : fs_) {
    if (!(ok = g_.linearizeFactorAt(f, 1.0, false, positions_.data(), result))) break;
    cost += g_.lastCost();
  }
  if (!ok || !std::isfinite(cost)) {
    result->status = Status();
    return false;
  }
  return true;
}

}  // namespace hamal::aprilsam
