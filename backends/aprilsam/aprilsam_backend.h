// AprilSamBackend: the AprilSAM algorithm (thesis ch. 3, Alg. 3.1) put
// together from its named parts:
//   - LinearizedGraph: the graph G with its linearisation points, the
//     estimate and the system R, y, dx held for them (sec. 3.3);
//   - BlockNormalEquations / JacobianRows: A_new, b_new of the step's
//     factors (eq. 3.5-3.7);
//   - IncrementalCholesky: R and y updated on the affected rows (eq. 3.14,
//     3.19, figs. 3.5-3.6);
//   - PartialBacksolve: dx from R dx = y, partial or full (fig. 3.7);
//   - UpdatePolicy: incremental or batch (sec. 3.4.4), with
//     LoopClosureGrid's COUNTPOSSIBLELOOPCLOSURENODES (line 9);
//   - BatchUpdate: lines 12-16, with the orderings of sec. 3.4.3;
//   - TopReelimination: iSAM2's alternative to the batch (reeliminate=top);
//   - ModeTracking and ComponentSwitchHook: factors with modes (a
//     max-mixture, ch. 4) in R, dormant ones out (core/dormant_policy.h).
//
// A step: AugmentGraph (line 2) appends the new variables at the end of the
// order between batches, linearised at their initial guess, and linearises
// the new factors at their variables' linearisation points; the first
// update, one after a failed batch and one that fixes a variable that has a
// column run a batch; the others update R incrementally, solve, and let the
// policy decide whether a batch (or the top's re-elimination) follows.
//
// Numerical failure: when an incremental update meets a diagonal block that
// is not positive definite, the step falls back to a batch with
// Levenberg-style damping (A_ii += lambda diag(A_ii)), and says so in the
// reason; when that fails too the Status names the variable. Nothing aborts.
//
// Marginal covariances (core/marginals.h, marginal_covariance.h) come from R
// as it is, at the linearisation points, without a solve or a refactoring.
// Refused (a Status) when the last update did not end ok or R holds a
// damped batch.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "backends/aprilsam/aprilsam_options.h"
#include "backends/aprilsam/batch_update.h"
#include "backends/aprilsam/component_switch_hook.h"
#include "backends/aprilsam/linearized_graph.h"
#include "backends/aprilsam/loop_closure_grid.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/aprilsam/top_backoff.h"
#include "backends/aprilsam/top_reelimination.h"
#include "backends/aprilsam/update_policy.h"
#include "core/backend.h"
#include "core/closing_verdict.h"
#include "core/factor_weights.h"
#include "core/marginals.h"
#include "core/phase_clock.h"

namespace hamal {

class AprilSamBackend : public Backend,
                        public FactorWeights,
                        public MarginalCovariances,
                        public ClosingVerdict {
 public:
  explicit AprilSamBackend(aprilsam::AprilSamOptions options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return graph_.variables().estimate(); }
  // The covariance of R's system, at the linearisation points (see above).
  Status jointMarginalCovariance(const std::vector<Key>& keys,
                                 Eigen::MatrixXd* covariance) override;

  // The run is over (core/closing_verdict.h): a full back-substitution.
  // The partial one leaves a row's dx as it was when its change is under
  // backsolve_tolerance (GTSAM's wildfire threshold), so between batches
  // the estimate lags R's own solution a little; at the end nothing is
  // saved by that (iSAM2's calculateBestEstimate). ok, or a numerical
  // failure when the solution is not finite (the estimate then stays at
  // the linearisation points). Nothing to do after a failed or damped
  // batch, or with backsolve=full or a tolerance of 0.
  Status closingVerdict() override;

  // Factor weights (core/factor_weights.h): R holds each factor at the
  // weight it had when it was linearised; the next update takes the
  // difference out and in at the factor's linearisation point, in the same
  // refactorisation of the affected rows as the step's new factors (a
  // reweighted factor is a change of H like a relinearised one), so only
  // the rows below the factor's variables are refactored. Weight 0 leaves
  // the factor's rows out; its place in the ordering stays until a batch.
  void setFactorWeight(const Factor* factor, double weight) override;
  double factorWeight(const Factor* factor) const override;
  // G from R (residual_covariance.h). False after a failed or damped batch
  // (R is not the undamped system) or for a factor on a variable it does
  // not hold (the factor itself need not be held).
  bool residualCovariance(const std::vector<const Factor*>& factors, Eigen::MatrixXd* g) override;
  // The next update is a full batch when a variable of `factors` is due for
  // relinearisation by the top re-elimination's rule (TopReelimination::due):
  // staleness below delta_T matters for a closure whose heading
  // information is 1e4 per rad^2.
  bool relinearizeAtNextUpdate(const std::vector<const Factor*>& factors) override;

  // For tests: the factor and its order (position of a variable, the
  // variable at a position), and each variable's linearisation point.
  const aprilsam::IncrementalCholesky& factor() const { return graph_.chol(); }
  const aprilsam::PartialBacksolve& backsolve() const { return graph_.solve(); }
  int positionOf(Key key) const {  // -1: fixed
    return graph_.order().posOf(graph_.variables().at(key));
  }
  Key keyAt(int position) const { return graph_.variables().key(graph_.order().varAt(position)); }
  const Values::Entry& linearizationPoint(Key key) const {
    return graph_.variables().lin(graph_.variables().at(key));
  }
  const std::vector<FactorPtr>& factors() const { return graph_.factors().all(); }
  int batches() const { return batch_.batches(); }
  // Factors with modes that the last batch left out as dormant.
  long dormantFactors() const { return graph_.modes().dormant_count; }

 private:
  // AugmentGraph (Alg. 3.1 line 2): the step's variables and factors; the
  // index of its first factor. `refixed`: a known variable is fixed now,
  // which takes its column out of R, as only a batch can.
  std::size_t augmentGraph(const Step& step, bool* refixed);
  // Alg. 3.1 lines 3-11 for the step's factors from `first_new` on: the
  // incremental update, its solve and the batch decision. False when the
  // step is not counted (its factors could not be linearised).
  bool incrementalUpdate(const Step& step, std::size_t first_new, PhaseClock* clock,
                         UpdateResult* result);
  // Alg. 3.1 lines 9-11 after an incremental solve that cost `flops`.
  void decide(double flops, PhaseClock* clock, UpdateResult* result);
  // After a back-substitution: false (result's status set) when the
  // estimate it gave is not finite, which then goes back to the
  // linearisation points, R marked broken.
  bool finiteOrReset(UpdateResult* result);
  // What the update policy weighs: this incremental cost against the last
  // batch's, and the possible loop-closure nodes.
  aprilsam::UpdateCosts updateCosts(double incremental) const;
  // A batch and the mode switches after its solve.
  void batchAndSwitch(const std::string& reason, bool damped, PhaseClock* clock,
                      UpdateResult* result);
  // A batch decision carried out: the top re-eliminated where
  // reeliminate=top and it applies, else a batch and the switches after it,
  // or, when `solved` (the step's own update and solve are done) and the
  // top over top_share follows batches that made no progress, nothing
  // (TopBackoff).
  void batchOrTop(const std::string& reason, bool solved, PhaseClock* clock, UpdateResult* result);

  aprilsam::AprilSamOptions options_;
  aprilsam::UpdatePolicy policy_;
  aprilsam::LinearizedGraph graph_;
  aprilsam::LoopClosureGrid grid_;
  aprilsam::OrderingWorkspace ordering_workspace_;  // the min-heap ordering's lists, reused
  aprilsam::BatchUpdate batch_;
  aprilsam::ComponentSwitchHook switch_hook_;
  aprilsam::TopReelimination top_;
  aprilsam::TopBackoff backoff_;
  long steps_ = 0;
  Status last_status_;        // of the last update that got past checkStep
  bool relinearize_ = false;  // relinearizeAtNextUpdate was asked
};

}  // namespace hamal
