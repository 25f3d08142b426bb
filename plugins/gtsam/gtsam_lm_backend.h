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

#include "core/backend.h"
#include "core/registry.h"
#include "gtsam_whole_graph.h"

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
  const Values& estimate() const override { return whole_.estimate; }

 private:
  GtsamLmOptions options_;
  GtsamWholeGraph whole_;
};

// The registry entry "gtsam-lm".
BackendInfo gtsamLmInfo();

}  // namespace hamal::gtsam_plugin
