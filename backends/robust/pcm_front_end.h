// PcmFrontEnd: Pairwise Consistency Maximization (Mangelson, Dominic,
// Eustice, Vasudevan, ICRA 2018) in front of any back-end. Candidate
// factors (the loop closures a predicate names) are held back until PCM
// accepts them; everything else, odometry included, goes straight to the
// inner back-end, which then optimises only what PCM let through, with
// whatever model it has (least squares, a robust loss, GNC).
//
// Steps. The first step that brings candidates runs batch PCM over them
// (pairwise_consistency_maximization.h): a batch solve is one step holding
// everything. Each later candidate goes through incremental PCM
// (incremental_pairwise_consistency_maximization.h), one at a time in step
// order, with its bounded cost per step. The odometry chain is every
// non-candidate factor between consecutive pose ids with a relativePose()
// (odometry_chain.h). Where it has gaps, or the graph several components,
// pairs of candidates no odometry joins are neither tested nor in conflict
// (pairwise_consistency_maximization.h, "Pairs the odometry cannot test"):
// a candidate that alone joins a new pose across a gap is accepted untested
// and passed on in its step. uncheckedPairs() counts such pairs.
//
// The estimate's test. With pcm_covariance=estimate (the default) and an
// inner back-end that gives residualCovariance (core/factor_weights.h:
// aprilsam, aprilsam-top), each candidate that arrives once the inner
// back-end holds an estimate is first tested against that estimate at the
// start of its step, with that estimate's covariance
// (estimate_consistency.h); one that fails is rejected for good and never
// joins PCM's consistency graph, the others go through PCM as above. Other
// back-ends, and a batch solve (nothing is held before its one step), use
// the odometry alone.
//
// Decisions that change. A candidate PCM rejects now and accepts later is
// passed on in the step that accepts it. One it accepted earlier and
// rejects later stays in the inner back-end (most back-ends cannot remove a
// factor): decisions() reports it rejected, inInner() says it is there, and
// keptRejected() counts such factors.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "backends/robust/incremental_pairwise_consistency_maximization.h"
#include "backends/robust/odometry_chain.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "backends/robust/truncated_objective_check.h"
#include "core/backend.h"
#include "core/closing_verdict.h"

namespace hamal::robust {

class PcmFrontEnd : public Backend, public ClosingVerdict {
 public:
  using Candidate = std::function<bool(const Factor&)>;
  // Throws hamal::Error when inner or is_candidate is empty or the options
  // are out of range (pcmOptionsFrom checks them first when they come from
  // a spec).
  PcmFrontEnd(std::unique_ptr<Backend> inner, Candidate is_candidate,
              const PcmOptions& options = defaultPcmOptions());

  // Checks the step (core/step.h), runs PCM on its candidates, passes the
  // rest and the newly accepted candidates to the inner back-end. PCM's
  // time is added to time.other.
  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return inner_->estimate(); }

  // Every candidate so far, in arrival order, with PCM's current decision.
  std::vector<std::pair<const Factor*, bool>> decisions() const;
  // Whether candidate `index` (of decisions()) was passed to the inner back-end.
  bool inInner(std::size_t index) const { return passed_.at(index); }
  // Candidates in the inner back-end that PCM now rejects.
  std::size_t keptRejected() const;
  // Where the estimate's test finds the estimate and its covariance when
  // the inner back-end is a wrapper (GNC around aprilsam): a function giving
  // the wrapped back-end, or null while there is none. By default the inner
  // back-end itself.
  using EstimateSource = std::function<Backend*()>;
  void setEstimateSource(EstimateSource source) { estimate_source_ = std::move(source); }
  // The back-end the estimate's test reads now (null: none).
  Backend* estimateSource() const { return estimate_source_ ? estimate_source_() : inner_.get(); }
  // The doubt rule (truncated_objective_check.h): an update that ends ok is
  // judged by it, and ends kUncertain when GNC-TLS from the answer finds a
  // cheaper map. None by default. Where the inner back-end gives its
  // residual covariance, the share rule weighs the map's refutation of the
  // rejected closures (near_misses.h), as GNC's does.
  void setAnswerCheck(std::unique_ptr<TruncatedObjectiveCheck> check);
  long answerChecks() const { return check_ ? check_->checks() : 0; }
  // The check on the answer as it stands (ok without one).
  Status closingVerdict() override;
  // Candidates rejected by the estimate's test (estimate_consistency.h).
  std::size_t estimateRejected() const { return estimate_rejected_; }
  // Pairs of candidates no odometry joins (not tested, not in conflict).
  std::size_t uncheckedPairs() const { return pcm_.uncheckedPairs(); }
  // Whether every PCM decision so far came from an exact clique search.
  bool exact() const { return exact_; }
  const Backend& inner() const { return *inner_; }
  const IncrementalPairwiseConsistencyMaximization& pcm() const { return pcm_; }

 private:
  std::unique_ptr<Backend> inner_;
  Candidate is_candidate_;
  OdometryChain chain_;
  PcmOptions options_;
  IncrementalPairwiseConsistencyMaximization pcm_;
  std::size_t estimate_rejected_ = 0;
  EstimateSource estimate_source_;
  std::unique_ptr<TruncatedObjectiveCheck> check_;
  std::vector<FactorPtr> candidates_;
  std::vector<bool> passed_;
  bool exact_ = true;
};

}  // namespace hamal::robust
