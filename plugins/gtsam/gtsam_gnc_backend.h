// GtsamGncBackend: GTSAM's GncOptimizer (graduated non-convexity, Yang,
// Antonante, Tzoumas, Carlone, RA-L 2020, as GTSAM implements it) as the
// hamal back-end "gtsam-gnc", so that hamal's own GNC
// (backends/robust/graduated_non_convexity.h) is compared with GTSAM's in
// one robust benchmark run (apps/robust) and graded the same way.
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
// GncOptimizer does not report its outer iterations; the inner optimizer
// is given through a parameter type whose optimizer counts its
// constructions (GncOptimizer makes one per outer iteration, after one for
// the all-inlier start). A run that uses every outer iteration it may is
// not converged (kNotConverged with the count), as gtsam-lm reports
// reaching its max_iterations; a GTSAM exception or a non-finite estimate is
// a numerical failure. The final weights are offered as InlierDecisions
// (core/inlier_decisions.h): rejected is a weight below 0.5 for TLS (whose
// weights end at 0 or 1) and below 1/4 for GM (the weight GM gives a
// residual at the threshold when mu = 1), the rule of hamal's GNC.
#pragma once

#include <vector>

#include "core/backend.h"
#include "core/inlier_decisions.h"
#include "core/registry.h"
#include "gtsam_whole_graph.h"

namespace hamal::gtsam_plugin {

struct GtsamGncOptions {
  enum class Loss { kTls, kGm };
  enum class Base { kLevenbergMarquardt, kGaussNewton };
  Loss loss = Loss::kTls;
  Base base = Base::kLevenbergMarquardt;
  double probability = 0.99;
  double threshold = 0;  // c2 in chi2 units when > 0 (overrides probability)
  double mu_step = 1.4;
  int max_iterations = 100;          // GNC's outer iterations
  double function_tolerance = 1e-5;  // GTSAM's relativeCostTol
  double weight_tolerance = 1e-4;    // GTSAM's weightsTol
  int base_max_iterations = 100;     // GTSAM's defaults for the inner optimizer
  double base_function_tolerance = 1e-5;
  double base_absolute_function_tolerance = 1e-5;
};

class GtsamGncBackend : public Backend, public InlierDecisions {
 public:
  explicit GtsamGncBackend(const GtsamGncOptions& options) : options_(options) {}

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return whole_.estimate; }
  std::vector<Decision> inlierDecisions() const override;

 private:
  GtsamGncOptions options_;
  GtsamWholeGraph whole_;
  std::vector<FactorPtr> owner_;  // whole_.graph[i]'s hamal factor; null for a fixed prior
  std::vector<bool> candidate_;   // whole_.graph[i] may be rejected
  std::vector<double> weights_;   // GNC's final weight of whole_.graph[i]
};

// The registry entry "gtsam-gnc".
BackendInfo gtsamGncInfo();

}  // namespace hamal::gtsam_plugin
