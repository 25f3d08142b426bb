// TruncatedObjectiveCheck: the doubt rules of answer_doubt.h ("a cheap
// alternative beats it", "most closures rejected") for PCM's front end and
// max-mixtures started at the map, and for GNC at the end of a run
// (backends/robust/README.md, "When the answer is in doubt").
//
// PCM decides by pairwise consistency and max-mixtures by each closure's
// active component; neither looks at the map the decisions make, so either
// can end far from the map the data support and still converge: PCM
// rejecting true closures whose odometry chain is overconfident, a
// max-mixture whose null hypothesis won at a distorted estimate. Both are
// judged here by the objective GNC-TLS minimises (truncatedObjective):
// every known inlier in full, each loop closure capped at its c2 (for a
// max-mixture, its nominal component). The alternatives are GNC-TLS over
// the whole graph started from the answer, GNC-TLS over the closures the
// answer leaves beyond their c2 (the map it gave up, as GNC's own rule
// tries), and GNC-TLS over the whole graph from the odometry composed from
// the first pose (a start the answer's decisions have not shaped), each
// then least squares over the closures that fit it. When the best is below the answer's objective
// by more than the smallest c2, the answer is not the better minimum. With the rule "most closures
// rejected" (answer_doubt.h; a closure counts as rejected when the answer leaves it beyond c2,
// whatever the model's own decision), the update's status becomes kUncertain naming what fired. An
// answer that leaves no closure beyond c2 is its own alternative and is not re-solved. The
// alternatives are solved when the closures have doubled since they last were, so an incremental
// run pays for about log2(n) triples of batch solves (GNC's own rule, whose alternative is one
// solve, rechecks at a quarter); the share, O(n) evaluations, when they have grown by a quarter.
// Between checks the last verdict stands.
//
// At the end of a run (judge with `now`) one more rule, noise_scale.h: where
// the answer's own residuals show the stated noise overstated by a wide
// factor, the alternative from the answer over every closure is solved again
// at c2 scaled by that factor, and cheaper there by more than the stated c2 it
// makes the answer kUncertain as well. Its map is offered apart
// (takeNoiseScaleMap), for a caller that takes the decisions it makes.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/noise_scale.h"
#include "core/backend.h"
#include "core/factor_weights.h"

namespace hamal::robust {

class TruncatedObjectiveCheck {
 public:
  using Predicate = std::function<bool(const Factor&)>;
  // `make` makes a plain (least-squares) back-end for the alternative;
  // `is_candidate` picks the loop closures; `gnc` gives their c2 and the
  // alternative's annealing. Throws hamal::Error when make or is_candidate
  // is empty. `starts` picks the alternatives' starts (all three unless
  // told otherwise).
  struct Starts {
    bool answer_every = true;     // from the answer, every closure
    bool answer_rejected = true;  // from the answer, the closures beyond c2
    bool odometry = true;         // from the odometry's own start, every closure
  };
  TruncatedObjectiveCheck(std::function<std::unique_ptr<Backend>()> make, Predicate is_candidate,
                          GncOptions gnc, Starts starts);
  TruncatedObjectiveCheck(std::function<std::unique_ptr<Backend>()> make, Predicate is_candidate,
                          GncOptions gnc)
      : TruncatedObjectiveCheck(std::move(make), std::move(is_candidate), gnc, Starts{}) {}

  // Records a step's factors and fixed variables (before the update).
  void add(const Step& step);
  // After an update that ended ok at `answer`: runs the check when due (or,
  // with `now`, whenever closures came since the last one: the run is over)
  // and returns the standing verdict (ok, or kUncertain naming the figures).
  Status judge(const Values& answer, bool now = false);

  long checks() const { return checks_; }
  // The map of the alternative that made the standing verdict doubt (a
  // cheaper one), taken once: nothing when there is none or it was taken.
  std::optional<Values> takeCheaperMap();
  // The same for the noise scale's alternative (its map at the scaled c2).
  std::optional<Values> takeNoiseScaleMap();
  // At the end of a run, where the answer shows the noise overstated, a
  // plain alternative cheaper at the stated c2 is doubt only if it is
  // cheaper at the scaled c2 too (the data's own units; off by default).
  void judgeAtNoiseScale(bool on) { judge_at_noise_scale_ = on; }
  // Runs every check on `answer` now, whatever is due (after the answer
  // was replaced by the cheaper map); with `now`, the end-of-run rule too.
  Status judgeAgain(const Values& answer, bool now = false);
  // The back-end whose residual covariance (at the answer the check is
  // given) weighs the rule "most closures rejected" by the false closures
  // the rejected ones predict among the accepted (near_misses.h); null (the
  // default) leaves the share alone as the rule.
  void weighNearMisses(FactorWeights* weights) { near_misses_ = weights; }

 private:
  // The objective of GNC-TLS over the inliers and the candidates in `use`,
  // started from `start` and polished; false when it cannot be made.
  bool alternative(const Values& start, const std::vector<bool>& use, const GncOptions& gnc,
                   const std::vector<double>& c2, double* objective, Values* at) const;
  // The cheapest alternative of the starts (`beyond`: the closures the
  // answer leaves beyond c2); infinity when none can be made.
  double bestAlternative(const Values& answer, const std::vector<bool>& beyond, Values* best) const;
  double objective(const Values& values, const std::vector<double>& c2) const;
  // The rule of noise_scale.h on `answer`, whose variance factor `scale`
  // shows the noise overstated: ok, or kUncertain (its map kept in
  // noise_cheaper_).
  Status noiseScale(const Values& answer, const NoiseScale& scale);
  // The answer's variance factor where it shows the stated noise overstated
  // (noise_scale.h), else nothing.
  std::optional<NoiseScale> overstatedNoise(const Values& answer) const;
  // Whether `other` is not cheaper than the answer by more than `margin`
  // at c2 scaled by the answer's variance factor `scale`.
  bool preferredAtNoiseScale(const Values& answer, const Values& other, double margin,
                             const NoiseScale& scale) const;
  Status verdict() const;  // the standing verdicts together

  std::function<std::unique_ptr<Backend>()> make_;
  Predicate is_candidate_;
  GncOptions gnc_;
  Starts starts_;
  std::vector<FactorPtr> inliers_;
  std::vector<FactorPtr> candidates_;  // nominal components for max-mixtures
  std::vector<double> c2_;
  std::vector<Key> fixed_;
  Values guesses_;                      // each variable's first guess, as its step brought it
  std::size_t checked_candidates_ = 0;  // at the last alternatives
  std::size_t shared_candidates_ = 0;   // at the last share
  std::size_t noise_candidates_ = 0;    // at the last noise-scale rule
  Status alternative_, share_, noise_;
  std::optional<Values> cheaper_;        // the alternative behind alternative_'s doubt
  std::optional<Values> noise_cheaper_;  // the one behind noise_'s
  long checks_ = 0;
  bool judge_at_noise_scale_ = false;
  FactorWeights* near_misses_ = nullptr;
  static constexpr double kRecheckGrowth = 2;
  static constexpr double kShareGrowth = 1.25;
};

}  // namespace hamal::robust
