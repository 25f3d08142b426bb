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
double weightedChi2(const FactorTable& factors, const Values& estimate) {
  double total = 0;
  for (std::size_t f = 0; f < factors.size(); ++f)
    if (factors.weight(f) > 0)
      total += factors.weight(f) * robustChi2(*factors.factor(f), estimate);
  return total;
}

}  // namespace

void BatchUpdate::addFactorEdges(int f) {
  const IndexRange vars = g_.factors().vars(f);
  for (const int* i = vars.begin(); i < vars.end();
       ++i)  // one-sided lists: the orderings symmetrise
    for (const int* j = i + 1; j < vars.end(); ++j) ordering_input_.adjacency[*i].push_back(*j);
}

void BatchUpdate::run(const std::string& reason, bool damped, PhaseClock* clock,
                      UpdateResult* result) {
  const double start = clock->seconds();
  VariableTable& vars = g_.variables();
  BatchRecord& record = g_.record();
  const int n = vars.size();
  result->kind = UpdateKind::kBatch;
  result->reason = reason;
  // Alg. 3.1 line 12: every linearisation point moves to the estimate.
  for (int v = 0; v < n; ++v) vars.moveLinearizationPoint(v);
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
  const bool check_rise = batches_ == 0 || record.broken;
  const double before = check_rise ? weightedChi2(g_.factors(), vars.estimate()) : 0.0;
  clock->lap(&result->time.other);
  double lambda = options_.batch.damping;
  for (long it = 0; it < options_.batch.iterations; ++it) {
    if (!iterate(dims, &damped, &lambda, clock, result)) return;
    if (it + 1 < options_.batch.iterations)
      for (int v = 0; v < n; ++v) vars.moveLinearizationPoint(v);
    clock->lap(&result->time.solve);
  }
  result->iterations = static_cast<int>(options_.batch.iterations);
  record.broken = false;
  grid_.refile(vars.linPoints());
  ++batches_;
  record.damped = damped;
  record.factors_at_top = g_.factors().size();
  record.last_batch_cost = options_.policy.cost == UpdatePolicyOptions::Cost::kWallclock
                               ? clock->seconds() - start
                               : g_.chol().totalFlops();
  const double after = check_rise ? weightedChi2(g_.factors(), vars.estimate()) : 0.0;
  // A rise within rounding (relative or, at an exact fit, absolute) is a
  // step taken at the optimum, not an overshoot.
  if (check_rise && std::isfinite(before) &&
      !(after <= before * (1 + kRoundingRise) + kRoundingRise) && result->status.ok()) {
    std::ostringstream why;
    why << "aprilsam: the batch's " << options_.batch.iterations
        << " Gauss-Newton step(s) (batch_iterations) raised the cost from " << before << " to "
        << after;
    result->status.code = Status::kNotConverged;
    result->status.message = why.str();
  }
  clock->lap(&result->time.other);
}

std::vector<int> BatchUpdate::layOutOrder() {
  // Fixed variables have no position: the order holds the free ones.
  const VariableTable& vars = g_.variables();
  std::vector<int> order;
  order.reserve(vars.size());
  for (int v : computeOrdering())
    if (!vars.fixed(v)) order.push_back(v);
  return g_.layOutOrder(order);
}

bool BatchUpdate::iterate(const std::vector<int>& dims, bool* damped, double* lambda,
                          PhaseClock* clock, UpdateResult* result) {
  const VariableTable& vars = g_.variables();
  const EliminationOrder& order = g_.order();
  IncrementalCholesky& chol = g_.chol();
  PartialBacksolve& solve = g_.solve();
  BlockNormalEquations& neq = g_.neq();
  const int m = static_cast<int>(dims.size());
  neq.clear(m);
  const bool linearized = g_.linearizeFactors(0, g_.factors().size(), false, result);
  g_.modes().at_lin_known = false;
  if (!linearized) {
    g_.record().broken = true;
    return false;
  }
  g_.factors().clearReweighted();  // every factor is in at its weight now
  clock->lap(&result->time.linearize);
  chol.reset(dims);
  if (*damped) neq.damp(*lambda, 1e-9);
  IncrementalCholesky::Outcome out = chol.update(neq, true);
  if (!out.ok) {
    // A part of the graph that nothing anchors would be damped into one of
    // its many optima and called ok; say what is missing instead, as every
    // back-end does (core/gauge_freedom.h). Asked only here, where the
    // factorisation meets the singular pivot such a part makes.
    std::vector<Key> fixed;
    for (int v = 0; v < vars.size(); ++v)
      if (vars.fixed(v)) fixed.push_back(vars.key(v));
    result->status = gaugeFreedomStatus("aprilsam", vars.keys(), g_.factors().all(), fixed);
    if (!result->status.ok()) {
      g_.record().broken = true;
      chol.reset(dims);
      solve.reset(m);
      return false;
    }
  }
  for (int attempt = 0; !out.ok && attempt < 6; ++attempt) {
    const Key bad = vars.key(order.varAt(out.failed_position));
    if (!*damped) {
      result->reason += "; batch not positive definite at " + bad.str() + ": damped";
      *damped = true;
    } else {
      *lambda *= 10;
    }
    // damp() adds, so the total damping is the sum of the steps.
    neq.damp(*lambda, 1e-9);
    out = chol.update(neq, true);
  }
  clock->lap(&result->time.factor);
  if (!out.ok) {
    const Key bad = vars.key(order.varAt(out.failed_position));
    result->status = Status::numericalFailure(
        "aprilsam: the normal equations are not positive definite at " + bad.str() +
            " even with damping (is the variable constrained?)",
        {bad});
    g_.record().broken = true;
    chol.reset(dims);
    solve.reset(m);
    return false;
  }
  result->columns_recomputed += out.columns_recomputed;
  solve.reset(m);
  solve.solve(chol, true, 0.0);
  g_.applyBatchDx();
  if (!g_.estimateIsFinite(result)) {
    g_.record().broken = true;
    return false;
  }
  return true;
}

std::vector<int> BatchUpdate::computeOrdering() {
  const VariableTable& vars = g_.variables();
  const int n = vars.size();
  if (options_.ordering == AprilSamOptions::Ordering::kNatural) {
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    return order;
  }
  OrderingInput& in = ordering_input_;
  in.positions.resize(n);
  for (int v = 0; v < n; ++v) in.positions[v] = vars.orderingPosition(v);
  in.newest = vars.newestPose();
  ModeTracking& modes = g_.modes();
  if (!modes.factors.empty()) {
    // The factors with modes that are not dormant at the linearisation
    // points (run has just moved them) join a copy of the graph.
    moded_ordering_input_ = in;
    modes.dormant_count = 0;
    for (int f : modes.factors) {
      // The batch's linearisation reads this mode back (modes.at_lin_known)
      // rather than evaluating every mixture a second time.
      modes.lin_mode[f] = g_.modeAtLinearizationPoint(f);
      if (modes.dormant(*modes.of_factor[f], modes.lin_mode[f])) {
        ++modes.dormant_count;
        continue;
      }
      const IndexRange fv = g_.factors().vars(f);
      for (const int* i = fv.begin(); i < fv.end(); ++i)
        for (const int* j = i + 1; j < fv.end(); ++j)
          moded_ordering_input_.adjacency[*i].push_back(*j);
    }
    modes.at_lin_known = true;
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
