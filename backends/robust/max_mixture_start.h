// MaxMixtureStart: where max-mixture loop closures (Olson & Agarwal,
// "Inference on networks of mixtures for robust robot mapping", RSS 2012;
// factors/max_mixture_factor.h, the model of the thesis' FLAG, ch. 4) start,
// so that odometry drift cannot switch a true closure off.
//
// Why. A max-mixture's active component is the one with the larger
// weighted likelihood at the estimate. From the odometry's guess a true
// closure at the end of a long loop carries the loop's whole drift, far
// beyond the null hypothesis' crossover (chi2 ~ 92 at Vertigo's null_weight
// 0.01 and null_scale 1e-12): the null hypothesis wins, the closure pulls
// nothing, the loop never closes and the next closure sees the same drift.
// On a clean graph with few closures per pose or a long drift before the
// first closure, most true closures end switched off.
//
// The rule (a wrapper around any back-end, as GraduatedNonConvexity is):
// a loop closure with modes (Factor::hasModes, nominal = modeComponent(0))
// starts at a map that drift does not decide:
//  - A batch (the first step that brings such closures while the inner
//    back-end holds nothing): graduated non-convexity (GNC-TLS,
//    graduated_non_convexity.h, at the given options) solves the step with
//    each mixture's nominal component as a candidate; a fresh inner
//    back-end then gets the step with the mixtures, starting from GNC's
//    estimate when GNC's status is ok, else (GNC not converged or in
//    doubt) from the step's guesses. GNC's first iterate is least squares: on a clean graph the
//    clean optimum, where no true closure is beyond the crossover; with
//    false closures GNC's truncated loss has already let go of them.
//  - A later step (the thesis protocol): a new mixture to a pose new in the
//    step whose nominal chi2 at the odometry's guess is beyond `crossover`
//    (where its null hypothesis wins: 92.1 at Vertigo's null_weight 0.01 and
//    null_scale 1e-12) but that agrees with the map, its Mahalanobis
//    distance against the estimate and its covariance (estimate_consistency.h)
//    below `threshold` (chi2 3 dof at 0.99 in hamal_robust), gives that
//    pose's guess (x_j = x_i z, the best-agreeing closure when several do)
//    in place of the odometry's. It starts at its nominal component and the
//    back-end closes the loop with it; the mixture keeps or switches it at
//    the estimates that follow. Any other closure, and every closure of a
//    back-end that gives no covariance (FactorWeights::residualCovariance:
//    aprilsam and aprilsam-top do, cholesky and ceres do not), keeps the
//    odometry's guess.
// Nothing else changes: the factors, and which component is active after
// the start, are the inner back-end's. Unless the GNC options' doubt is off,
// an update that ends ok is then judged by TruncatedObjectiveCheck, and
// ends kUncertain when GNC-TLS from the answer finds a cheaper map.
#pragma once

#include <functional>
#include <memory>

#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/odometry_chain.h"
#include "backends/robust/truncated_objective_check.h"
#include "core/backend.h"
#include "core/closing_verdict.h"

namespace hamal::robust {

class MaxMixtureStart : public Backend, public ClosingVerdict {
 public:
  using Predicate = std::function<bool(const Factor&)>;
  // `make` makes the inner back-end (once more for a batch start);
  // `is_candidate` picks the loop closures (those with modes are started);
  // `threshold`: the Mahalanobis distance (squared) below which a closure
  // agrees with the map; `crossover`: the chi2 beyond which its null
  // hypothesis wins. Throws hamal::Error when make or is_candidate is empty
  // or a threshold is not positive.
  MaxMixtureStart(std::function<std::unique_ptr<Backend>()> make, Predicate is_candidate,
                  GncOptions gnc, double threshold, double crossover);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return inner_->estimate(); }
  const Backend& inner() const { return *inner_; }

  // Whether the first batch started from GNC's estimate, and how many poses
  // of later steps were guessed from a closure.
  bool startedFromGnc() const { return started_from_gnc_; }
  std::size_t guessedFromClosures() const { return guessed_from_closures_; }
  // The doubt rule's checks so far (truncated_objective_check.h; none when
  // the GNC options' doubt is off).
  long answerChecks() const { return check_ ? check_->checks() : 0; }
  // The check on the answer as it stands (ok without one).
  Status closingVerdict() override;

 private:
  UpdateResult start(const Step& step);  // the rule above
  UpdateResult batchStart(const Step& step);
  Step guessFromClosures(const Step& step);

  std::function<std::unique_ptr<Backend>()> make_;
  Predicate is_candidate_;
  GncOptions gnc_;
  double threshold_, crossover_;
  std::unique_ptr<Backend> inner_;
  std::unique_ptr<TruncatedObjectiveCheck> check_;
  OdometryChain chain_;
  bool started_from_gnc_ = false;
  std::size_t guessed_from_closures_ = 0;
};

}  // namespace hamal::robust
