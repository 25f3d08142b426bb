// AprilSamBackend: see aprilsam_backend.h (thesis ch. 3, Alg. 3.1).
#include "backends/aprilsam/aprilsam_backend.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <utility>

#include "backends/aprilsam/marginal_covariance.h"
#include "backends/aprilsam/residual_covariance.h"
#include "core/error.h"

namespace hamal {

// The class is hamal's (a registered back-end); its parts are aprilsam's.
using aprilsam::AprilSamOptions;
using aprilsam::IncrementalCholesky;
using aprilsam::UpdateCosts;
using aprilsam::UpdateDecision;
using aprilsam::UpdatePolicyOptions;

AprilSamBackend::AprilSamBackend(AprilSamOptions options)
    : options_(std::move(options)),
      policy_(options_.policy),
      graph_(options_.dormant_scale, options_.policy.delta_t),
      grid_(options_.loop_closure_radius, options_.n_lc),
      batch_(options_, &graph_, &grid_, &ordering_workspace_),
      switch_hook_(options_, &graph_, &batch_),
      top_(options_, &graph_, &ordering_workspace_),
      backoff_(options_.top.backoff) {}

void AprilSamBackend::setFactorWeight(const Factor* factor, double weight) {
  const int f = graph_.factors().find(factor);
  if (f < 0) throw Error("aprilsam: factor weight of a factor it does not hold");
  if (!(weight >= 0) || !std::isfinite(weight))
    throw Error("aprilsam: factor weight " + std::to_string(weight) +
                " is not a finite number >= 0");
  graph_.factors().setWeight(f, weight);
}

double AprilSamBackend::factorWeight(const Factor* factor) const {
  const int f = graph_.factors().find(factor);
  if (f < 0) throw Error("aprilsam: factor weight of a factor it does not hold");
  return graph_.factors().weight(f);
}

bool AprilSamBackend::residualCovariance(const std::vector<const Factor*>& factors,
                                         Eigen::MatrixXd* g) {
  // R must be the undamped system.
  if (graph_.record().broken || graph_.record().damped) return false;
  return aprilsam::residualCovariance(graph_.variables(), graph_.order(), graph_.chol(), factors,
                                      g);
}

bool AprilSamBackend::relinearizeAtNextUpdate(const std::vector<const Factor*>& factors) {
  for (const Factor* factor : factors)
    for (const Key& key : factor->keys()) {
      const int v = graph_.variables().find(key);
      relinearize_ |= v >= 0 && top_.due(v);
    }
  return relinearize_;
}

UpdateCosts AprilSamBackend::updateCosts(double incremental) const {
  UpdateCosts costs;
  costs.incremental = incremental;
  costs.batch = graph_.record().last_batch_cost;
  costs.possible_loop_closure_nodes = grid_.countPossibleLoopClosureNodes(
      graph_.variables().newestPose(), graph_.variables().linPoints());
  return costs;
}

void AprilSamBackend::batchAndSwitch(const std::string& reason, bool damped, PhaseClock* clock,
                                     UpdateResult* result) {
  batch_.run(reason, damped, clock, result);
  switch_hook_.run(clock, result);
}

void AprilSamBackend::batchOrTop(const std::string& reason, bool solved, PhaseClock* clock,
                                 UpdateResult* result) {
  if (options_.reeliminate != AprilSamOptions::Reeliminate::kTop) {
    batchAndSwitch(reason, false, clock, result);
    return;
  }
  if (top_.run(reason, clock, result)) {
    backoff_.reset();
    return;
  }
  if (!top_.oversized()) {
    batchAndSwitch(reason, false, clock, result);
    return;
  }
  const long moved = graph_.moved().size();
  if (solved && backoff_.hold(steps_, moved)) {
    result->reason = reason + "; top over top_share after batches that left L no smaller: " +
                     "incremental until update " + std::to_string(backoff_.until());
    return;
  }
  batchAndSwitch(reason, false, clock, result);
  backoff_.batched(steps_, moved);
}

std::size_t AprilSamBackend::augmentGraph(const Step& step, bool* refixed) {
  // New variables at the end of the order; a fixed one keeps its value and
  // gets no position (core/step.h).
  const std::unordered_set<Key> new_fixed(step.fixed.begin(), step.fixed.end());
  for (const Key& key : step.new_values.keys()) {
    const int v = graph_.addVariable(key, step.new_values.entry(key), new_fixed.count(key) > 0);
    batch_.addVariable();
    grid_.insert(v, graph_.variables().lin(v));
  }
  *refixed = false;
  for (const Key& key : step.fixed) {
    const int v = graph_.variables().at(key);
    if (graph_.variables().fixed(v)) continue;
    graph_.variables().fix(v);
    *refixed = true;
  }
  const std::size_t first_new = graph_.factors().size();
  for (const FactorPtr& f : step.new_factors) {
    const int index = graph_.addFactor(f);
    if (!graph_.modes().of_factor[index])
      batch_.addFactorEdges(index);  // moded ones join each batch
  }
  return first_new;
}

UpdateResult AprilSamBackend::update(const Step& step) {
  UpdateResult result;
  PhaseClock clock;
  // The one input contract (core/step.h): bad input throws before anything
  // is recorded and leaves the back-end as it was.
  checkStep(step, graph_.variables().estimate(), "aprilsam");
  bool refixed = false;
  const std::size_t first_new = augmentGraph(step, &refixed);
  clock.lap(&result.time.other);

  bool counted = true;
  const bool relinearize = std::exchange(relinearize_, false);
  if (graph_.record().broken) {
    batchAndSwitch("the previous batch failed", false, &clock, &result);
  } else if (refixed) {
    batchAndSwitch("a known variable was fixed", false, &clock, &result);
  } else if (steps_ == 0) {
    // The first update is always a batch (UpdatePolicy): there is no order
    // yet, and an incremental pass in arrival order would only add fill.
    batchAndSwitch("first update", false, &clock, &result);
  } else if (relinearize) {
    // A caller reweighting factors asked for it (factor_weights.h): a full
    // batch, which takes the step's factors and every pending reweighting in
    // at the estimate (a top re-elimination would keep the old rows of the
    // reweighted factors' ancestors).
    batchAndSwitch("relinearisation asked by the factor weights' caller", false, &clock, &result);
  } else {
    counted = incrementalUpdate(step, first_new, &clock, &result);
  }
  if (counted) ++steps_;
  result.variables = graph_.variables().size();
  result.columns_total = graph_.chol().columnsTotal();
  // What no phase counted (the switch passes after a batch, say) is other.
  clock.finish(&result.time);
  last_status_ = result.status;
  return result;
}

Status AprilSamBackend::jointMarginalCovariance(const std::vector<Key>& keys,
                                                Eigen::MatrixXd* covariance) {
  checkMarginalKeys(keys, graph_.variables().estimate(), "aprilsam");
  if (!last_status_.ok())
    return Status::numericalFailure(
        "aprilsam: no marginal covariance: the last update did not end ok (" +
            last_status_.message + ")",
        last_status_.keys);
  if (graph_.record().broken || graph_.record().damped)
    return Status::numericalFailure(
        "aprilsam: no marginal covariance: R holds a failed or damped batch, not the system");
  Eigen::MatrixXd out =
      aprilsam::marginalCovariance(graph_.variables(), graph_.order(), graph_.chol(), keys);
  if (!out.allFinite())
    return Status::numericalFailure("aprilsam: the marginal covariance is not finite", keys);
  *covariance = std::move(out);
  return Status();
}

Status AprilSamBackend::closingVerdict() {
  if (steps_ == 0 || !last_status_.ok() || graph_.record().broken || graph_.record().damped ||
      options_.backsolve.kind == AprilSamOptions::Backsolve::kFull ||
      options_.backsolve.tolerance <= 0)
    return Status();
  graph_.solve().solve(graph_.chol(), true, 0.0);
  graph_.applyChangedDx();
  UpdateResult check;
  finiteOrReset(&check);
  return check.status;
}

bool AprilSamBackend::finiteOrReset(UpdateResult* result) {
  if (graph_.estimateIsFinite(result)) return true;
  // Back to the linearisation points, which are finite; the next update
  // is a batch from there.
  graph_.resetChangedEstimates();
  graph_.record().broken = true;
  return false;
}

bool AprilSamBackend::incrementalUpdate(const Step& step, std::size_t first_new, PhaseClock* clock,
                                        UpdateResult* result) {
  // Alg. 3.1 lines 3-4: the incremental update (eq. 3.14, 3.19) and the
  // back-substitution.
  long new_rows = 0;
  for (const FactorPtr& f : step.new_factors) new_rows += f->residualDim();
  // Reweighted factors take weight out as well as in: not a rank update.
  const bool as_rows = options_.factor_update == AprilSamOptions::FactorUpdate::kRank &&
                       new_rows <= options_.rank_update_max_rows &&
                       graph_.factors().reweighted().empty();
  IncrementalCholesky& chol = graph_.chol();
  graph_.neq().clear(chol.size());
  graph_.rows().clear();
  if (!graph_.linearizeFactors(first_new, graph_.factors().size(), as_rows, result) ||
      !graph_.reweighFactors(result))
    return false;
  clock->lap(&result->time.linearize);
  if (options_.batch_first && as_rows &&
      options_.policy.cost == UpdatePolicyOptions::Cost::kDeterministic) {
    // batch_first: the criteria that do not read the step's solve (the
    // cost one, with the flops the rank update would report, and the
    // periodic one) are asked first; when they call for a batch, the rank
    // update and its solve are not run, and the batch starts from the
    // estimate before them (the new variables at their guesses). With
    // reeliminate=top the step's new factors enter the top's H in full
    // (every variable they touch is in the top), so the top, like a batch,
    // needs no rank update before it.
    const UpdateDecision early =
        policy_.decide(steps_, 0, 0.0, updateCosts(chol.addRowsFlops(graph_.rows())));
    clock->lap(&result->time.other);
    if (early.batch) {
      batchOrTop(early.reason, false, clock, result);
      return true;
    }
  }
  const IncrementalCholesky::Outcome out =
      as_rows ? chol.addRows(graph_.rows()) : chol.update(graph_.neq(), false);
  clock->lap(&result->time.factor);
  if (!out.ok) {
    const Key bad = graph_.variables().key(graph_.order().varAt(out.failed_position));
    batchAndSwitch("incremental update not positive definite at " + bad.str() + ": damped batch",
                   true, clock, result);
    return true;
  }
  graph_.solve().solve(chol, options_.backsolve.kind == AprilSamOptions::Backsolve::kFull,
                       options_.backsolve.tolerance);
  graph_.applyChangedDx();
  clock->lap(&result->time.solve);
  result->kind = UpdateKind::kIncremental;
  result->columns_recomputed = out.columns_recomputed;
  if (!finiteOrReset(result)) return true;
  decide(out.flops, clock, result);
  return true;
}

void AprilSamBackend::decide(double flops, PhaseClock* clock, UpdateResult* result) {
  // Alg. 3.1 lines 5-11: the batch decision.
  const auto ask = [&] {
    const double incremental =
        options_.policy.cost == UpdatePolicyOptions::Cost::kWallclock
            ? result->time.linearize + result->time.factor + result->time.solve
            : flops;
    return policy_.decide(steps_, graph_.moved().size(), graph_.moved().dxNorm(),
                          updateCosts(incremental));
  };
  // A batch relinearises every variable and checks every mode after its
  // solve, so switch passes before it would be refactored away: they run
  // only when the step stays incremental, and the decision is taken again
  // after them (they move the estimate, so |L| and ||dx||).
  UpdateDecision decision = ask();
  clock->lap(&result->time.other);
  if (!decision.batch) {
    switch_hook_.run(clock, result);
    clock->lap(&result->time.factor);
    if (result->kind == UpdateKind::kIncremental) decision = ask();
    clock->lap(&result->time.other);
  }
  if (decision.batch) {
    batchOrTop(decision.reason, true, clock, result);
  } else {
    backoff_.reset();
    result->reason = decision.reason + result->reason;
  }
}

}  // namespace hamal
