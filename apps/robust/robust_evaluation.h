// RobustEvaluation: how the robust benchmark grades one estimate of a
// spoiled graph (apps/robust/README.md): the trajectory error against the
// clean graph's batch optimum after a rigid alignment (core/metrics.h), the
// share of false edges switched off (recall) and of true loop closures
// switched off by mistake (nullHypothesisActive), and chi2 over the clean
// graph's factors, the objective the robust models should not have spoiled.
#pragma once

#include <cstddef>
#include <vector>

#include "apps/robust/false_loop_closures.h"
#include "apps/robust/robust_loop_closures.h"
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
  // The false edges left on (null hypothesis not active), as indices into
  // the spoiled graph's factors: what the accepted-edges diagnosis of
  // hamal_robust adds to the clean graph.
  std::vector<std::size_t> false_accepted;

  double recall() const;           // NaN without false edges
  double trueSwitchedOff() const;  // NaN without true loop closures
};

// The clean graph's factors: those of `spoiled` not in `false_edges`.
std::vector<FactorPtr> cleanFactors(const Graph& spoiled,
                                    const std::vector<FalseEdge>& false_edges);

// `estimate` must hold every variable of `spoiled`, all finite (hamal::Error
// otherwise: a run that diverged has no figures to grade).
RobustEvaluation evaluateRobust(const Graph& spoiled, const std::vector<FalseEdge>& false_edges,
                                const Values& estimate, const Values& clean_optimum,
                                const RobustOptions& options);

}  // namespace hamal::apps
