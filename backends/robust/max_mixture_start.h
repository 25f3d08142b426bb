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
// a loop closure with modes (core/multi_modal.h, nominal = modeComponent(0))
// starts at a map that drift does not decide:
//  - A batch (the first step that brings such closures while the inner
//    back-end holds nothing): least squares over the step with each
//    mixture's nominal component, from `initialize`'s values (LAGO in
//    hamal_robust; none: this start is skipped), iterated to convergence;
//    where it leaves every closure within its c2 (GNC's inlier threshold),
//    that is the start, since GNC-TLS would anneal nothing and answer it.
//    Else graduated non-convexity (GNC-TLS, graduated_non_convexity.h, at
//    the given options) solves the step with the nominal components as
//    candidates, and the start is GNC's estimate when GNC's status is ok,
//    else (GNC not converged or in doubt) the step's guesses. A fresh inner
//    back-end gets the step with the mixtures from the start. A back-end
//    that stops at its iteration limit from the odometry never reaches the
//    clean optimum, and LS from the odometry can end in another basin
//    (ais2klinik: 136 m off at chi2 181.5 against 172.7); LAGO's start
//    does not.
//  - A later step (the thesis protocol): a new mixture to a pose new in the
//    step whose nominal chi2 at the odometry's guess is beyond `crossover`
//    (where its null hypothesis wins: 92.1 at Vertigo's null_weight 0.01 and
//    null_scale 1e-12) but that agrees with the map, its Mahalanobis
//    distance against the estimate and its covariance (estimate_consistency.h)
//    below `threshold` (chi2 3 dof at 0.99 in hamal_robust), gives that
//    pose's guess (x_j = x_i z, the best-agreeing closure when several do)
//    in place of the odometry's. It starts at its nominal component and the
//    back-end closes the loop with it. Any other closure, and every closure
//    of a back-end that gives no covariance (FactorWeights::residualCovariance:
//    aprilsam and aprilsam-top do, cholesky and ceres do not), keeps the
//    odometry's guess.
//  - Closed again (after an update that brought mixtures): a closure that
//    should hold (on before the update, or new and agreeing with the map as
//    above) but ends switched off (its nominal chi2 beyond `crossover`):
//    another closure of the step gave the pose's guess, or the solve passed
//    beyond the crossover on its way (a closure far tighter across than
//    along, as MIT's, crosses it at centimetres). Least squares over the
//    inliers and every closure that should hold or is on, from the answer
//    and iterated to convergence; where it leaves each of them within the
//    crossover, a fresh inner back-end gets every factor so far from there.
//  - Adopted: unless the GNC options' doubt is off, an update that ends ok
//    is judged by TruncatedObjectiveCheck; when it finds a cheaper map
//    (truncated objective lower by more than the smallest c2: closures the
//    estimate's test turned away as the drift made them disagree, MIT's
//    x315-x12 at d2 40), a fresh inner back-end gets every factor so far
//    from that map and is judged again; the update ends kUncertain if the
//    doubt stands. A restart that stops at its iteration limit goes on from
//    there (kRestartRounds fresh back-ends) and else ends not_converged.
// The factors, and which component is active after a start, are the inner
// back-end's. One closure switched off alone moves the truncated objective
// by at most its c2, which the doubt rule does not call cheaper: the
// re-closing rule is what closes it.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <vector>

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
  using Initializer = std::function<Values(const Step&)>;
  MaxMixtureStart(std::function<std::unique_ptr<Backend>()> make, Predicate is_candidate,
                  GncOptions gnc, double threshold, double crossover,
                  Initializer initialize = nullptr);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return inner_->estimate(); }
  const Backend& inner() const { return *inner_; }

  // Whether the first batch started from GNC's estimate, and how many poses
  // of later steps were guessed from a closure.
  bool startedFromGnc() const { return started_from_gnc_; }
  bool startedFromLeastSquares() const { return started_from_least_squares_; }
  std::size_t guessedFromClosures() const { return guessed_from_closures_; }
  // How often the mixtures were started again: from least squares where a
  // closure that should hold was switched off, and from a cheaper map the
  // doubt rule found.
  long reclosed() const { return reclosed_; }
  long adopted() const { return adopted_; }
  // The doubt rule's checks so far (truncated_objective_check.h; none when
  // the GNC options' doubt is off).
  long answerChecks() const { return check_ ? check_->checks() : 0; }
  // The check on the answer as it stands (ok without one).
  Status closingVerdict() override;

 private:
  UpdateResult start(const Step& step);  // the rule above
  UpdateResult batchStart(const Step& step);
  Step guessFromClosures(const Step& step);
  // A fresh inner back-end over every factor so far, started at `from`;
  // false (the old one kept) when it does not end ok and finite.
  bool restart(const Values& from, UpdateResult* r);
  // The re-closing rule (above) after an update that brought the mixtures
  // from `first_new` on.
  void reclose(std::size_t first_new, UpdateResult* r);
  // Least squares over `problem` from its values (converged, at most
  // kLeastSquaresRounds batch updates); false on a failure.
  bool leastSquares(const Step& problem, Values* at) const;
  static constexpr int kLeastSquaresRounds = 20;
  static constexpr int kRestartRounds = 3;
  static constexpr double kLeastSquaresTolerance = 1e-6;
  // Whether mixture k's nominal component wins at `values`.
  bool on(std::size_t k, const Values& values) const;

  std::function<std::unique_ptr<Backend>()> make_;
  Initializer initialize_;
  Predicate is_candidate_;
  GncOptions gnc_;
  double threshold_, crossover_;
  std::unique_ptr<Backend> inner_;
  std::unique_ptr<TruncatedObjectiveCheck> check_;
  OdometryChain chain_;
  std::vector<FactorPtr> factors_;   // every factor so far, as the steps brought them
  std::vector<FactorPtr> inliers_;   // those that are no candidates
  std::vector<FactorPtr> nominals_;  // each mixture's nominal component
  std::vector<bool> on_;             // ... winning at the estimate after the last update
  std::vector<bool> agreed_;         // ... agreeing with the map when it came
  std::vector<Key> fixed_;
  std::map<const Factor*, std::size_t> index_;  // a mixture's place in nominals_
  bool started_from_gnc_ = false, started_from_least_squares_ = false;
  std::size_t guessed_from_closures_ = 0;
  long reclosed_ = 0, adopted_ = 0;
};

}  // namespace hamal::robust
