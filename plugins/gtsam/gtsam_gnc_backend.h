// GtsamGncBackend: GTSAM's GncOptimizer (graduated non-convexity, Yang,
// Antonante, Tzoumas, Carlone, RA-L 2020, as GTSAM implements it) as the
// hamal back-end "gtsam-gnc", so that hamal's own GNC
// (backends/robust/graduated_non_convexity.h) is compared with GTSAM's in
// one hamal_robust invocation and graded the same way.
//
// Every update() adds the step and runs GncOptimizer over the whole graph
// from the current estimate, over GTSAM's Levenberg-Marquardt or
// Gauss-Newton (GTSAM's own loop: each outer iteration re-solves the
// weighted graph from the initial values). Loop closures
// (backends/robust/loop_closure.h) are the factors GNC may reject; every
// other factor, and the priors that hold fixed variables, are GNC's known
// inliers, as in hamal's GNC. The options default to GTSAM's (TLS, inlier
// threshold the chi2 quantile of each factor's dimension at 0.99, mu step
// 1.4, 100 outer iterations).
//
// GncOptimizer does not report whether it converged or how many outer
// iterations it took; the status is ok unless GTSAM throws (numerical
// failure) or the estimate is not finite. The final weights are offered as
// InlierDecisions (core/inlier_decisions.h): rejected is a weight below 0.5
// for TLS (whose weights end at 0 or 1) and below 1/4 for GM (the weight GM
// gives a residual at the threshold when mu = 1), the rule of hamal's GNC.
#pragma once

#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/Values.h>

#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/inlier_decisions.h"
#include "core/registry.h"

namespace hamal::gtsam_plugin {

struct GtsamGncOptions {
  enum class Loss { kTls, kGm };
  enum class Base { kLevenbergMarquardt, kGaussNewton };
  Loss loss = Loss::kTls;
  Base base = Base::kLevenbergMarquardt;
  double probability = 0.99;
  double mu_step = 1.4;
  int max_iterations = 100;  // GNC's outer iterations
  double relative_cost_tol = 1e-5;
  double weights_tol = 1e-4;
  int base_max_iterations = 100;  // GTSAM's defaults for the inner optimizer
  double base_relative_error_tol = 1e-5;
  double base_absolute_error_tol = 1e-5;
};

class GtsamGncBackend : public Backend, public InlierDecisions {
 public:
  explicit GtsamGncBackend(const GtsamGncOptions& options) : options_(options) {}

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return estimate_; }
  std::vector<Decision> inlierDecisions() const override;

 private:
  GtsamGncOptions options_;
  gtsam::NonlinearFactorGraph graph_;
  std::vector<FactorPtr> owner_;  // graph_[i]'s hamal factor; null for a fixed prior
  std::vector<bool> candidate_;   // graph_[i] may be rejected
  gtsam::Values values_;
  Values estimate_;
  std::vector<double> weights_;  // GNC's final weight of graph_[i]
  std::vector<Key> fixed_;
  std::unordered_set<Key> fixed_set_;
  std::size_t columns_total_ = 0;
};

// The registry entry "gtsam-gnc".
BackendInfo gtsamGncInfo();

}  // namespace hamal::gtsam_plugin
