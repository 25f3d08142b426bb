// RobustEvaluation: see robust_evaluation.h.
#include "apps/robust/robust_evaluation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <unordered_map>

#include "backends/robust/dynamic_covariance_scaling.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/pcm_front_end.h"
#include "core/error.h"
#include "core/inlier_decisions.h"

namespace hamal::apps {

double RobustEvaluation::recall() const {
  return false_edges ? double(false_switched_off) / false_edges
                     : std::numeric_limits<double>::quiet_NaN();
}

double RobustEvaluation::precision() const {
  const std::size_t rejected = false_switched_off + true_switched_off;
  return rejected ? double(false_switched_off) / rejected
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

ModelDecisions modelDecisions(const Graph& spoiled, const Backend& model_backend,
                              const Values& estimate, const RobustOptions& options) {
  ModelDecisions out;
  const std::size_t n = spoiled.factors.size();
  std::unordered_map<const Factor*, std::size_t> index;
  for (std::size_t i = 0; i < n; ++i) index.emplace(spoiled.factors[i].get(), i);
  const Backend* inner = &model_backend;
  if (const auto* pcm = dynamic_cast<const robust::PcmFrontEnd*>(&model_backend)) {
    // PCM's rejections stand; what it accepted the inner model decides.
    out.rejected.assign(n, -1);
    out.weight.assign(n, std::numeric_limits<double>::quiet_NaN());
    for (const auto& [factor, accepted] : pcm->decisions()) {
      const auto it = index.find(factor);
      if (it == index.end()) continue;
      out.rejected[it->second] = accepted ? 0 : 1;
      out.weight[it->second] = accepted ? 1 : 0;
    }
    inner = &pcm->inner();
  }
  if (const auto* gnc = dynamic_cast<const robust::GraduatedNonConvexity*>(inner)) {
    out.rejected.resize(n, -1);
    out.weight.resize(n, std::numeric_limits<double>::quiet_NaN());
    for (const auto& d : gnc->decisions()) {
      const auto it = index.find(d.factor);
      if (it == index.end() || out.rejected[it->second] == 1) continue;
      out.rejected[it->second] = gnc->rejected(d.weight) ? 1 : 0;
      out.weight[it->second] = d.weight;
    }
  } else if (const auto* own = dynamic_cast<const InlierDecisions*>(inner)) {
    // A back-end robust by itself (gtsam-gnc): its own verdicts.
    out.rejected.resize(n, -1);
    out.weight.resize(n, std::numeric_limits<double>::quiet_NaN());
    out.threshold.resize(n, 0);
    for (const auto& d : own->inlierDecisions()) {
      const auto it = index.find(d.factor);
      if (it == index.end() || out.rejected[it->second] == 1) continue;
      out.rejected[it->second] = d.rejected ? 1 : 0;
      out.weight[it->second] = d.weight;
      out.threshold[it->second] = d.threshold;
    }
  } else if (options.method == RobustMethod::kDcs) {
    out.rejected.assign(n, -1);
    out.weight.assign(n, std::numeric_limits<double>::quiet_NaN());
    const robust::DynamicCovarianceScaling dcs(options.dcs_phi);
    for (std::size_t i = 0; i < n; ++i) {
      const Factor& f = *spoiled.factors[i];
      if (!isLoopClosure(f)) continue;
      const double s = f.chi2(estimate);
      out.rejected[i] = s > robust::chiSquareQuantile(f.residualDim(), 0.99) ? 1 : 0;
      out.weight[i] = dcs.weight(s);
    }
  }
  return out;
}

double truncatedObjective(const Graph& graph, const Values& values, const RobustOptions& options,
                          const ModelDecisions* decisions) {
  double total = 0;
  for (std::size_t i = 0; i < graph.factors.size(); ++i) {
    const Factor& f = *graph.factors[i];
    const double s = f.chi2(values);
    if (!isLoopClosure(f)) {
      total += s;
      continue;
    }
    const bool stated = decisions && i < decisions->threshold.size() && decisions->threshold[i] > 0;
    total += std::min(s, stated ? decisions->threshold[i] : options.gnc.threshold(f.residualDim()));
  }
  return total;
}

RobustEvaluation evaluateRobust(const Graph& spoiled, const std::vector<FalseEdge>& false_edges,
                                const Values& estimate, const Values& clean_optimum,
                                const RobustOptions& options, const ModelDecisions* decisions) {
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
    const auto off_now = [&] {
      if (decisions && i < decisions->rejected.size() && decisions->rejected[i] >= 0)
        return decisions->rejected[i] == 1;
      return nullHypothesisActive(f, estimate, options);
    };
    if (is_false.count(i)) {
      ++ev.false_edges;
      const bool off = off_now();
      ev.false_switched_off += off;
      if (!off) ev.false_accepted.push_back(i);
    } else if (isLoopClosure(*f)) {
      ++ev.true_loop_closures;
      ev.true_switched_off += off_now();
    }
  }
  ev.chi2_true = chi2(cleanFactors(spoiled, false_edges), estimate);
  ev.tls_objective = truncatedObjective(spoiled, estimate, options, decisions);
  ev.tls_objective_clean = truncatedObjective(spoiled, clean_optimum, options, decisions);
  return ev;
}

}  // namespace hamal::apps
