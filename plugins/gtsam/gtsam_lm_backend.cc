// GtsamLmBackend: see gtsam_lm_backend.h.
#include "gtsam_lm_backend.h"

#include <gtsam/nonlinear/LevenbergMarquardtOptimizer.h>

#include <cmath>
#include <string>
#include <utility>

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

  whole_.add(step, kName);
  result.variables = whole_.estimate.size();
  result.columns_total = whole_.columns_total;
  result.time.other = phase.lap();
  if (whole_.graph.empty()) {
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
  gtsam::Values solved;
  try {
    gtsam::LevenbergMarquardtOptimizer optimizer(whole_.graph, whole_.values, params);
    solved = optimizer.optimize();
    iterations = optimizer.iterations();
    error = optimizer.error();
  } catch (...) {
    result.time.solve = phase.lap();
    result.status = gtsamFailure(kName);
    return result;
  }
  result.time.solve = phase.lap();
  whole_.accept(std::move(solved));
  result.time.estimate = phase.lap();

  result.iterations = static_cast<int>(iterations);
  result.variables_relinearized = whole_.estimate.size();
  result.columns_recomputed = whole_.columns_total * iterations;
  result.status = finiteEstimateStatus(whole_.estimate, kName);
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
