// GtsamWholeGraph: the whole graph a batch GTSAM back-end re-solves at every
// step (gtsam_lm_backend.h, gtsam_gnc_backend.h; thesis sec. 3.5, "batch"):
// GTSAM's factors and values, hamal's estimate and the fixed variables, fed
// one protocol step at a time. Both back-ends take a step the same way, so
// the intake is here once: everything that can refuse a step (checkStep,
// an unmapped factor) runs before anything is recorded.
#pragma once

#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/Values.h>

#include <string>
#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/step.h"
#include "core/values.h"

namespace hamal::gtsam_plugin {

struct GtsamWholeGraph {
  gtsam::NonlinearFactorGraph graph;
  gtsam::Values values;  // GTSAM's copy of the estimate, where the next solve starts
  Values estimate;
  std::vector<Key> fixed;  // held by strong priors (gtsam_factor_adapter.h)
  std::unordered_set<Key> fixed_set;
  std::size_t columns_total = 0;

  // Adds `step`: its factors, in order, as graph[first .. first +
  // step.new_factors.size()), then the priors of newly fixed variables.
  // Returns `first`. Throws hamal::Error naming `backend`, leaving
  // everything as it was, when the step is refused.
  std::size_t add(const Step& step, const std::string& backend);

  // GTSAM's solution `solved` becomes `values` and hamal's estimate (fixed
  // variables keep their value).
  void accept(gtsam::Values solved);
};

}  // namespace hamal::gtsam_plugin
