// GtsamLmBackend: see gtsam_lm_backend.h.
#include "gtsam_lm_backend.h"

#include <gtsam/nonlinear/LevenbergMarquardtOptimizer.h>

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/finite_result.h"
#include "core/stopwatch.h"
#include "gtsam_factor_adapter.h"

namespace hamal::gtsam_plugin {

namespace {
constexpr const char* kName = "gtsam-lm";
}  // namespace

UpdateResult GtsamLmBackend::update(const Step& step) {
  UpdateResult result;
  result.kind = UpdateKind::kBatch;
  result.reason = "GTSAM Levenberg-Marquardt over the whole graph";
  Stopwatch phase;

  // Everything that can refuse the step runs before anything is recorded.
  checkStep(step, estimate_, kName);
  gtsam::NonlinearFactorGraph factors = toGtsamFactors(step.new_factors, kName);
  const std::vector<Key> newly_fixed = addFixedPriors(step, estimate_, fixed_set_, &factors);

  for (const auto& [key, entry] : step.new_values) {
    estimate_.insertEntry(key, entry);
    insertGtsamValue(key, entry, &values_);
    columns_total_ += dimension(entry.type);
  }
  graph_.push_back(factors.begin(), factors.end());
  for (Key k : newly_fixed) {
    fixed_.push_back(k);
    fixed_set_.insert(k);
  }
  result.variables = estimate_.size();
  result.columns_total = columns_total_;
  result.time.other = phase.lap();
  if (graph_.empty()) {
    result.kind = UpdateKind::kNone;
    result.reason = "no factor yet";
    return result;
  }

  gtsam::LevenbergMarquardtParams params;
  params.maxIterations = options_.max_iterations;
  params.relativeErrorTol = options_.relative_error_tol;
  params.absoluteErrorTol = options_.absolute_error_tol;
  params.setVerbosityLM("SILENT");
  std::size_t iterations = 0;
  double error = 0;
  try {
    gtsam::LevenbergMarquardtOptimizer optimizer(graph_, values_, params);
    values_ = optimizer.optimize();
    iterations = optimizer.iterations();
    error = optimizer.error();
  } catch (...) {
    result.time.solve = phase.lap();
    result.status = gtsamFailure(kName);
    return result;
  }
  result.time.solve = phase.lap();
  copyFromGtsam(values_, fixed_, &estimate_);
  result.time.estimate = phase.lap();

  result.iterations = static_cast<int>(iterations);
  result.variables_relinearized = estimate_.size();
  result.columns_recomputed = columns_total_ * iterations;
  result.status = finiteEstimateStatus(estimate_, kName);
  if (result.status.ok() && !std::isfinite(error))
    result.status = Status::numericalFailure(std::string(kName) + ": GTSAM's error is not finite");
  if (result.status.ok() && iterations >= std::size_t(options_.max_iterations)) {
    result.status.code = Status::kNotConverged;
    result.status.message = std::string(kName) + ": stopped at max_iterations=" +
                            std::to_string(options_.max_iterations);
  }
  result.time.other += phase.lap();
  return result;
}

BackendInfo gtsamLmInfo() {
  BackendInfo info;
  info.name = kName;
  info.description =
      "GTSAM's batch Levenberg-Marquardt (GTSAM plugin): the whole graph re-solved every step "
      "from the current estimate; factors mapped to GTSAM's with hamal's objective";
  info.options = {
      {"max_iterations", "100",
       "LM iterations per update, at most (>= 1); reaching it is "
       "reported as not converged"},
      {"function_tolerance",
       "1e-10",
       "stop when the error decreases by less than this fraction (GTSAM's relativeErrorTol, "
       "default 1e-5; smaller here so that the solve reaches the optimum a reference needs; "
       "old name: relative_error_tol)",
       {"relative_error_tol"}},
      {"absolute_function_tolerance",
       "1e-10",
       "stop when the error (chi2 / 2) decreases by less than this (GTSAM's absoluteErrorTol, "
       "default 1e-5; old name: absolute_error_tol)",
       {"absolute_error_tol"}},
  };
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    GtsamLmOptions o;
    const long iterations = options.getInt("max_iterations");
    o.relative_error_tol = options.getDouble("function_tolerance");
    o.absolute_error_tol = options.getDouble("absolute_function_tolerance");
    if (iterations < 1) throw Error("gtsam-lm: option max_iterations must be at least 1");
    if (!(o.relative_error_tol >= 0.0) || !(o.absolute_error_tol >= 0.0))
      throw Error("gtsam-lm: the error tolerances must be >= 0");
    o.max_iterations = static_cast<int>(iterations);
    return std::make_unique<GtsamLmBackend>(o);
  };
  return info;
}

}  // namespace hamal::gtsam_plugin
