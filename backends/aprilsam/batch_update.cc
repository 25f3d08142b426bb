// BatchUpdate: see batch_update.h (thesis Alg. 3.1 lines 12-16, sec. 3.4.3).
#include "backends/aprilsam/batch_update.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "backends/aprilsam/bhamd_ordering.h"
#include "core/gauge_freedom.h"
#include "core/metrics.h"
#include "core/phase_clock.h"

namespace hamal::aprilsam {

namespace {

constexpr double kRoundingRise = 1e-9;

// sum w_f rho_f(chi2_f) at the estimate: the objective the batch minimises
// (a robust loss may let chi2 rise while it lets an outlier go).
double weightedChi2(const LinearizedGraph& g) {
  double total = 0;
  for (std::size_t f = 0; f < g.factors.size(); ++f)
    if (g.weight[f] > 0) total += g.weight[f] * robustChi2(*g.factors[f], g.estimate);
  return total;
}

}  // namespace

void BatchUpdate::addFactorEdges(int f) {
  const int b = g_.factor_begin[f], e = g_.factor_begin[f + 1];
  for (int i = b; i < e; ++i)  // one-sided lists: the orderings symmetrise
    for (int j = i + 1; j < e; ++j)
      ordering_input_.adjacency[g_.factor_vars[i]].push_back(g_.factor_vars[j]);
}

void BatchUpdate::run(const std::string& reason, bool damped, PhaseClock* clock,
                      UpdateResult* result) {
  const double start = clock->seconds();
  const int n = static_cast<int>(g_.keys.size());
  result->kind = UpdateKind::kBatch;
  result->reason = reason;
  // Alg. 3.1 line 12: every linearisation point moves to the estimate.
  for (int v = 0; v < n; ++v) g_.moveLinearizationPoint(v);
  result->variables_relinearized = n;
  clock->lap(&result->time.other);

  const std::vector<int> dims = layOutOrder();
  clock->lap(&result->time.order);

  // Whether the Gauss-Newton step(s) raised the cost is checked on a batch
  // that starts from guesses no batch has solved (the first, or the one
  // after a failure): that is where a full step overshoots (a batch from
  // the odometry guess). Later batches start where the incremental updates
  // kept the estimate, near the optimum; there the check's two passes over
  // every factor would add a large share of a batch's own cost for nothing.
  const bool check_rise = batches_ == 0 || g_.broken;
  const double before = check_rise ? weightedChi2(g_) : 0.0;
  clock->lap(&result->time.other);
  double lambda = options_.damping;
  for (long it = 0; it < options_.batch_iterations; ++it) {
    if (!iterate(dims, &damped, &lambda, clock, result)) return;
    if (it + 1 < options_.batch_iterations)
      for (int v = 0; v < n; ++v) g_.moveLinearizationPoint(v);
    clock->lap(&result->time.solve);
  }
  result->iterations = static_cast<int>(options_.batch_iterations);
  g_.broken = false;
  grid_.refile(g_.lin);
  ++batches_;
  g_.damped = damped;
  g_.factors_at_top = g_.factors.size();
  g_.last_batch_cost = options_.policy.cost == UpdatePolicyOptions::Cost::kWallclock
                           ? clock->seconds() - start
                           : g_.chol.totalFlops();
  const double after = check_rise ? weightedChi2(g_) : 0.0;
  // A rise within rounding (relative or, at an exact fit, absolute) is a
  // step taken at the optimum, not an overshoot.
  if (check_rise && std::isfinite(before) &&
      !(after <= before * (1 + kRoundingRise) + kRoundingRise) && result->status.ok()) {
    std::ostringstream why;
    why << "aprilsam: the batch's " << options_.batch_iterations
        << " Gauss-Newton step(s) (batch_iterations) raised the cost from " << before << " to "
        << after;
    result->status.code = Status::kNotConverged;
    result->status.message = why.str();
  }
  clock->lap(&result->time.other);
}

std::vector<int> BatchUpdate::layOutOrder() {
  // Fixed variables have no position: the order holds the free ones.
  std::vector<int> order;
  order.reserve(g_.keys.size());
  for (int v : computeOrdering())
    if (!g_.fixed[v]) order.push_back(v);
  const int m = static_cast<int>(order.size());
  g_.var_at = order;
  std::fill(g_.pos_of.begin(), g_.pos_of.end(), -1);
  for (int k = 0; k < m; ++k) g_.pos_of[order[k]] = k;
  std::vector<int> dims(m);
  for (int k = 0; k < m; ++k) dims[k] = g_.dims[order[k]];
  return dims;
}

bool BatchUpdate::iterate(const std::vector<int>& dims, bool* damped, double* lambda,
                          PhaseClock* clock, UpdateResult* result) {
  const int m = static_cast<int>(dims.size());
  g_.neq.clear(m);
  const bool linearized = g_.linearizeFactors(0, g_.factors.size(), false, result);
  g_.modes.at_lin_known = false;
  if (!linearized) {
    g_.broken = true;
    return false;
  }
  g_.reweighted.clear();  // every factor is in at its weight now
  clock->lap(&result->time.linearize);
  g_.chol.reset(dims);
  if (*damped) g_.neq.damp(*lambda, 1e-9);
  IncrementalCholesky::Outcome out = g_.chol.update(g_.neq, true);
  if (!out.ok) {
    // A part of the graph that nothing anchors would be damped into one of
    // its many optima and called ok; say what is missing instead, as every
    // back-end does (core/gauge_freedom.h). Asked only here, where the
    // factorisation meets the singular pivot such a part makes.
    std::vector<Key> fixed;
    for (std::size_t v = 0; v < g_.keys.size(); ++v)
      if (g_.fixed[v]) fixed.push_back(g_.keys[v]);
    result->status = gaugeFreedomStatus("aprilsam", g_.keys, g_.factors, fixed);
    if (!result->status.ok()) {
      g_.broken = true;
      g_.chol.reset(dims);
      g_.solve.reset(m);
      return false;
    }
  }
  for (int attempt = 0; !out.ok && attempt < 6; ++attempt) {
    const Key bad = g_.keys[g_.var_at[out.failed_position]];
    if (!*damped) {
      result->reason += "; batch not positive definite at " + bad.str() + ": damped";
      *damped = true;
    } else {
      *lambda *= 10;
    }
    // damp() adds, so the total damping is the sum of the steps.
    g_.neq.damp(*lambda, 1e-9);
    out = g_.chol.update(g_.neq, true);
  }
  clock->lap(&result->time.factor);
  if (!out.ok) {
    const Key bad = g_.keys[g_.var_at[out.failed_position]];
    result->status = Status::numericalFailure(
        "aprilsam: the normal equations are not positive definite at " + bad.str() +
            " even with damping (is the variable constrained?)",
        {bad});
    g_.broken = true;
    g_.chol.reset(dims);
    g_.solve.reset(m);
    return false;
  }
  result->columns_recomputed += out.columns_recomputed;
  g_.solve.reset(m);
  g_.solve.solve(g_.chol, true, 0.0);
  g_.dx_sq = 0;
  g_.moved_count = 0;
  std::fill(g_.dx_sq_of.begin(), g_.dx_sq_of.end(), 0.0);
  std::fill(g_.moved.begin(), g_.moved.end(), 0);
  g_.applyChangedDx();
  if (!g_.estimateIsFinite(result)) {
    g_.broken = true;
    return false;
  }
  return true;
}

std::vector<int> BatchUpdate::computeOrdering() {
  const int n = static_cast<int>(g_.keys.size());
  if (options_.ordering == AprilSamOptions::Ordering::kNatural) {
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    return order;
  }
  OrderingInput& in = ordering_input_;
  in.positions.resize(n);
  for (int v = 0; v < n; ++v) in.positions[v] = g_.orderingPosition(v);
  in.newest = g_.newest_pose;
  if (!g_.modes.factors.empty()) {
    // The factors with modes that are not dormant at the linearisation
    // points (run has just moved them) join a copy of the graph.
    moded_ordering_input_ = in;
    g_.modes.dormant_count = 0;
    for (int f : g_.modes.factors) {
      const int b = g_.factor_begin[f], e = g_.factor_begin[f + 1];
      g_.params.resize(e - b);
      for (int k = b; k < e; ++k) g_.params[k - b] = g_.lin[g_.factor_vars[k]].data.data();
      // The batch's linearisation reads this mode back (modes.at_lin_known)
      // rather than evaluating every mixture a second time.
      g_.modes.lin_mode[f] = g_.factors[f]->mode(g_.params.data());
      if (g_.modes.dormant(*g_.factors[f], g_.modes.lin_mode[f])) {
        ++g_.modes.dormant_count;
        continue;
      }
      for (int i = b; i < e; ++i)
        for (int j = i + 1; j < e; ++j)
          moded_ordering_input_.adjacency[g_.factor_vars[i]].push_back(g_.factor_vars[j]);
    }
    g_.modes.at_lin_known = true;
    if (options_.ordering == AprilSamOptions::Ordering::kMinHeap)
      return minHeapOrdering(moded_ordering_input_, options_.loop_closure_radius, &workspace_);
    if (options_.ordering == AprilSamOptions::Ordering::kBhamd)
      return bhamdOrdering(moded_ordering_input_);
    return amdOrdering(moded_ordering_input_);
  }
  if (options_.ordering == AprilSamOptions::Ordering::kMinHeap)
    return minHeapOrdering(in, options_.loop_closure_radius, &workspace_);
  if (options_.ordering == AprilSamOptions::Ordering::kBhamd) return bhamdOrdering(in);
  return amdOrdering(in);
}

}  // namespace hamal::aprilsam
