// RobustEvaluation: see robust_evaluation.h.
#include "apps/robust/robust_evaluation.h"

#include <cmath>
#include <limits>
#include <set>

#include "core/error.h"

namespace hamal::apps {

double RobustEvaluation::recall() const {
  return false_edges ? double(false_switched_off) / false_edges
                     : std::numeric_limits<double>::quiet_NaN();
}

double RobustEvaluation::trueSwitchedOff() const {
  return true_loop_closures ? double(true_switched_off) / true_loop_closures
                            : std::numeric_limits<double>::quiet_NaN();
}

std::vector<FactorPtr> cleanFactors(const Graph& spoiled,
                                    const std::vector<FalseEdge>& false_edges) {
  std::set<std::size_t> drop;
  for (const auto& e : false_edges) drop.insert(e.factor);
  std::vector<FactorPtr> out;
  for (std::size_t i = 0; i < spoiled.factors.size(); ++i)
    if (!drop.count(i)) out.push_back(spoiled.factors[i]);
  return out;
}

RobustEvaluation evaluateRobust(const Graph& spoiled, const std::vector<FalseEdge>& false_edges,
                                const Values& estimate, const Values& clean_optimum,
                                const RobustOptions& options) {
  for (Key k : spoiled.keys()) {
    if (!estimate.contains(k)) throw Error("the estimate lacks " + k.str());
    const auto& entry = estimate.entry(k);
    for (int d = 0; d < dimension(entry.type); ++d)
      if (!std::isfinite(entry.data[d]))
        throw Error("the estimate of " + k.str() + " is not finite");
  }
  RobustEvaluation ev;
  ev.ate = absoluteTrajectoryError(estimate, clean_optimum, true);
  std::set<std::size_t> is_false;
  for (const auto& e : false_edges) is_false.insert(e.factor);
  for (std::size_t i = 0; i < spoiled.factors.size(); ++i) {
    const FactorPtr& f = spoiled.factors[i];
    if (is_false.count(i)) {
      ++ev.false_edges;
      const bool off = nullHypothesisActive(f, estimate, options);
      ev.false_switched_off += off;
      if (!off) ev.false_accepted.push_back(i);
    } else if (isLoopClosure(*f)) {
      ++ev.true_loop_closures;
      ev.true_switched_off += nullHypothesisActive(f, estimate, options);
    }
  }
  ev.chi2_true = chi2(cleanFactors(spoiled, false_edges), estimate);
  return ev;
}

}  // namespace hamal::apps
