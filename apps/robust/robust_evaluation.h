// RobustEvaluation: how the robust benchmark grades one estimate of a
// spoiled graph (apps/robust/README.md): the trajectory error against the
// clean graph's batch optimum after a rigid alignment (core/metrics.h), the
// share of false edges rejected (recall), the share of rejected edges that
// are false (precision), true loop closures rejected by mistake, and chi2
// over the clean graph's factors, the objective the robust models should not
// have spoiled. "Rejected" is the model's own decision where it makes one
// (GNC: a final weight below its inlier level; DCS: a chi2 term beyond the
// inlier threshold, where its weight falls below the one it gives there);
// for the others (least squares, Cauchy, Huber, max-mixtures) it is the
// max-mixture rule (nullHypothesisActive), exact for max-mixture runs.
#pragma once

#include <cstddef>
#include <vector>

#include "apps/robust/false_loop_closures.h"
#include "apps/robust/robust_loop_closures.h"
#include "core/backend.h"
#include "core/graph.h"
#include "core/metrics.h"
#include "core/values.h"

namespace hamal::apps {

struct RobustEvaluation {
  TrajectoryError ate;  // estimate vs the clean optimum, aligned
  std::size_t false_edges = 0;
  std::size_t false_switched_off = 0;  // recall = this / false_edges
  std::size_t true_loop_closures = 0;
  std::size_t true_switched_off = 0;
  double chi2_true = 0;  // over the clean graph's factors, without losses
  // The truncated least-squares objective of the spoiled graph (every
  // factor's chi2, a loop closure's capped at its inlier threshold c2) at
  // the estimate and at the clean optimum. When the run's is the lower, the
  // clean map is not the objective's global minimum: an exact TLS solver
  // would not return it either, and the failure is the model's (threshold
  // and covariances), not the solver's.
  double tls_objective = 0;
  double tls_objective_clean = 0;
  // The false edges left on (null hypothesis not active), as indices into
  // the spoiled graph's factors: what the accepted-edges diagnosis of
  // hamal_robust adds to the clean graph.
  std::vector<std::size_t> false_accepted;

  double recall() const;           // NaN without false edges
  double precision() const;        // false / all rejected; NaN when nothing is rejected
  double trueSwitchedOff() const;  // NaN without true loop closures
};

// The model's own decision on each factor of the spoiled graph, by index:
// -1 none (graded by the max-mixture rule), 0 accepted, 1 rejected; and its
// weight (NaN where the model has none).
struct ModelDecisions {
  std::vector<signed char> rejected;
  std::vector<double> weight;
  // The inlier threshold c2 a back-end robust by itself stated for each
  // factor (InlierDecisions); empty or 0 where the run's GNC options give it.
  std::vector<double> threshold;
};

// The clean graph's factors: those of `spoiled` not in `false_edges`.
std::vector<FactorPtr> cleanFactors(const Graph& spoiled,
                                    const std::vector<FalseEdge>& false_edges);

// What `model_backend` (the back-end the run used, as hamal_robust's
// registry made it) decided about the spoiled graph's loop closures at
// `estimate`: the GNC wrapper's final weights, the verdicts of a back-end
// that offers InlierDecisions (core/inlier_decisions.h: gtsam-gnc), DCS's
// weight and threshold rule (chi2 beyond the chi2 quantile of the factor's
// dimension at 0.99), nothing for the other models.
ModelDecisions modelDecisions(const Graph& spoiled, const Backend& model_backend,
                              const Values& estimate, const RobustOptions& options);

// The truncated least-squares objective of `graph` at `values`: loop
// closures capped at their c2, every other factor in full. The c2 is the
// one `decisions` states for the factor (a back-end robust by itself, as
// gtsam-gnc with its threshold option), else the run's GNC options'
// (gnc_threshold, or the chi2 quantile of the closure's dimension at
// gnc_probability), so that both are graded at the threshold they ran with.
double truncatedObjective(const Graph& graph, const Values& values, const RobustOptions& options,
                          const ModelDecisions* decisions = nullptr);

// `estimate` must hold every variable of `spoiled`, all finite (hamal::Error
// otherwise: a run that diverged has no figures to grade).
RobustEvaluation evaluateRobust(const Graph& spoiled, const std::vector<FalseEdge>& false_edges,
                                const Values& estimate, const Values& clean_optimum,
                                const RobustOptions& options,
                                const ModelDecisions* decisions = nullptr);

}  // namespace hamal::apps
