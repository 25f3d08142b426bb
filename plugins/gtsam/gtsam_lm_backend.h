// GtsamLmBackend: GTSAM's batch Levenberg-Marquardt as the hamal back-end
// "gtsam-lm": the batch solver of the thesis' comparisons (sec. 3.5,
// "batch"), here GTSAM's own, on the objective hamal scores (the factors are
// mapped by gtsam_factor_adapter.h).
//
// Every update() adds the step and runs LevenbergMarquardtOptimizer over the
// whole graph from the current estimate (GTSAM's COLAMD ordering and
// multifrontal Cholesky). Under the thesis protocol that is one batch solve
// per pose, so it is meant for small graphs, for hamal_bench --batch, and as
// --reference gtsam-lm: an optimum from an independent solver.
//
// UpdateResult::time: other - converting the step; solve - the optimizer
// (GTSAM linearises, orders, factors and solves inside it and does not split
// the time); estimate - the copy of GTSAM's values into hamal's.
// A solve that stops at max_iterations is kNotConverged; a GTSAM exception (an
// indeterminant system: an unanchored graph) or a non-finite estimate is a
// numerical failure. Fixed variables are held by strong priors (see
// gtsam_factor_adapter.h).
#pragma once

#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/Values.h>

#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/registry.h"

namespace hamal::gtsam_plugin {

struct GtsamLmOptions {
  int max_iterations = 100;
  double relative_error_tol = 1e-10;
  double absolute_error_tol = 1e-10;
};

class GtsamLmBackend : public Backend {
 public:
  explicit GtsamLmBackend(const GtsamLmOptions& options) : options_(options) {}

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return estimate_; }

 private:
  GtsamLmOptions options_;
  gtsam::NonlinearFactorGraph graph_;
  gtsam::Values values_;  // GTSAM's copy of the estimate, where the next solve starts
  Values estimate_;
  std::vector<Key> fixed_;
  std::unordered_set<Key> fixed_set_;
  std::size_t columns_total_ = 0;
};

// The registry entry "gtsam-lm".
BackendInfo gtsamLmInfo();

}  // namespace hamal::gtsam_plugin
