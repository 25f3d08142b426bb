// GtsamGncBackend: see gtsam_gnc_backend.h.
#include "gtsam_gnc_backend.h"

#include <gtsam/nonlinear/GaussNewtonOptimizer.h>
#include <gtsam/nonlinear/GncOptimizer.h>
#include <gtsam/nonlinear/LevenbergMarquardtOptimizer.h>

#include <cmath>
#include <string>
#include <utility>

#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "core/finite_result.h"
#include "core/stopwatch.h"
#include "gtsam_factor_adapter.h"

namespace hamal::gtsam_plugin {

namespace {

constexpr const char* kName = "gtsam-gnc";

// The inner optimizer's parameters, with an optimizer type that counts its
// constructions: GncOptimizer makes one for the all-inlier start and one
// per outer iteration, and reports neither.
template <class BaseParams>
struct CountedParams : BaseParams {
  using Counted = typename BaseParams::OptimizerType;
  struct Optimizer : Counted {
    Optimizer(const gtsam::NonlinearFactorGraph& graph, const gtsam::Values& initial,
              const CountedParams& params)
        : Counted(graph, initial, params) {
      ++*params.solves;
    }
  };
  using OptimizerType = Optimizer;

  CountedParams(const BaseParams& base, std::size_t* counter) : BaseParams(base), solves(counter) {}
  std::size_t* solves;
};

struct GncRun {
  gtsam::Values values;
  std::size_t outer_iterations = 0;
};

template <class BaseParams>
GncRun runGnc(const gtsam::NonlinearFactorGraph& graph, const gtsam::Values& initial,
              BaseParams base, const GtsamGncOptions& o,
              const gtsam::FastVector<uint64_t>& known_inliers, std::vector<double>* weights) {
  base.maxIterations = o.base_max_iterations;
  base.relativeErrorTol = o.base_function_tolerance;
  base.absoluteErrorTol = o.base_absolute_function_tolerance;
  std::size_t solves = 0;
  using Params = gtsam::GncParams<CountedParams<BaseParams>>;
  Params params(CountedParams<BaseParams>(base, &solves));
  params.setLossType(o.loss == GtsamGncOptions::Loss::kTls ? gtsam::GncLossType::TLS
                                                           : gtsam::GncLossType::GM);
  // Set directly: setMaxIterations prints a warning to std::cout.
  params.maxIterations = static_cast<std::size_t>(o.max_iterations);
  params.setMuStep(o.mu_step);
  params.setRelativeCostTol(o.function_tolerance);
  params.setWeightsTol(o.weight_tolerance);
  params.setKnownInliers(known_inliers);
  gtsam::GncOptimizer<Params> gnc(graph, initial, params);
  // GTSAM's inlier cost is the factor's error, chi2 / 2.
  if (o.threshold > 0)
    gnc.setInlierCostThresholds(0.5 * o.threshold);
  else
    gnc.setInlierCostThresholdsAtProbability(o.probability);
  GncRun run;
  run.values = gnc.optimize();
  run.outer_iterations = solves > 0 ? solves - 1 : 0;
  const gtsam::Vector& w = gnc.getWeights();
  weights->assign(w.data(), w.data() + w.size());
  return run;
}

}  // namespace

UpdateResult GtsamGncBackend::update(const Step& step) {
  UpdateResult result;
  result.kind = UpdateKind::kBatch;
  result.reason = "GTSAM GncOptimizer over the whole graph";
  Stopwatch phase;

  const std::size_t first = whole_.add(step, kName);
  const std::size_t mapped = step.new_factors.size();
  for (std::size_t i = first; i < whole_.graph.size(); ++i) {
    const bool from_step = i - first < mapped;
    owner_.push_back(from_step ? step.new_factors[i - first] : nullptr);
    candidate_.push_back(from_step && robust::isLoopClosure(*step.new_factors[i - first]));
  }
  weights_.resize(whole_.graph.size(), 1.0);
  result.variables = whole_.estimate.size();
  result.columns_total = whole_.columns_total;
  result.time.other = phase.lap();
  if (whole_.graph.empty()) {
    result.kind = UpdateKind::kNone;
    result.reason = "no factor yet";
    return result;
  }

  gtsam::FastVector<uint64_t> known_inliers;
  for (std::size_t i = 0; i < whole_.graph.size(); ++i)
    if (!candidate_[i]) known_inliers.push_back(i);
  GncRun run;
  try {
    if (options_.base == GtsamGncOptions::Base::kLevenbergMarquardt) {
      gtsam::LevenbergMarquardtParams base;
      base.setVerbosityLM("SILENT");
      run = runGnc(whole_.graph, whole_.values, base, options_, known_inliers, &weights_);
    } else {
      run = runGnc(whole_.graph, whole_.values, gtsam::GaussNewtonParams(), options_, known_inliers,
                   &weights_);
    }
  } catch (...) {
    result.time.solve = phase.lap();
    result.status = gtsamFailure(kName);
    return result;
  }
  result.time.solve = phase.lap();
  whole_.accept(std::move(run.values));
  result.time.estimate = phase.lap();

  result.iterations = static_cast<int>(run.outer_iterations);
  result.variables_relinearized = whole_.estimate.size();
  result.status = finiteEstimateStatus(whole_.estimate, kName);
  if (result.status.ok() && run.outer_iterations >= std::size_t(options_.max_iterations)) {
    result.status.code = Status::kNotConverged;
    result.status.message = std::string(kName) + ": GNC used all " +
                            std::to_string(run.outer_iterations) +
                            " outer iterations (max_iterations) without converging";
  }
  result.time.other += phase.lap();
  return result;
}

std::vector<InlierDecisions::Decision> GtsamGncBackend::inlierDecisions() const {
  const double level = options_.loss == GtsamGncOptions::Loss::kTls ? 0.5 : 0.25;
  std::vector<Decision> out;
  for (std::size_t i = 0; i < whole_.graph.size(); ++i) {
    if (!candidate_[i]) continue;
    const Factor* f = owner_[i].get();
    // The c2 GncOptimizer ran with, in chi2 units (its inlier cost is half of it).
    const double c2 = options_.threshold > 0
                          ? options_.threshold
                          : robust::chiSquareQuantile(f->residualDim(), options_.probability);
    out.push_back({f, weights_[i], weights_[i] < level, c2});
  }
  return out;
}

BackendInfo gtsamGncInfo() {
  BackendInfo info;
  info.name = kName;
  info.description =
      "GTSAM's GncOptimizer (GTSAM plugin): graduated non-convexity over GTSAM's LM or "
      "Gauss-Newton, the whole graph every step; loop closures may be rejected, every other "
      "factor is a known inlier";
  info.options = {
      {"loss", "tls", "tls (truncated least squares) | gm (Geman-McClure)"},
      {"base", "lm", "the inner optimizer: lm (Levenberg-Marquardt) | gn (Gauss-Newton)"},
      {"probability", "0.99",
       "inlier threshold: the chi2 quantile of each factor's dimension at this probability, "
       "in (0, 1)"},
      {"threshold", "0",
       "inlier threshold c2 itself, in chi2 units, when > 0 (overrides probability; hamal's "
       "gnc_threshold)"},
      {"mu_step", "1.4", "factor of each mu update, > 1"},
      {"max_iterations", "100",
       "GNC's outer iterations, at most (>= 1); using them all is reported as not converged"},
      {"function_tolerance",
       "1e-5",
       "GNC stops when the weighted cost changes by less than this fraction (GTSAM's "
       "relativeCostTol)",
       {"relative_cost_tol"}},
      {"weight_tolerance",
       "1e-4",
       "GNC-TLS stops when every weight is this close to 0 or 1 (GTSAM's weightsTol)",
       {"weights_tol"}},
      {"base_max_iterations", "100", "the inner optimizer's iterations, at most (>= 1)"},
      {"base_function_tolerance",
       "1e-5",
       "the inner optimizer stops when its error decreases by less than this fraction "
       "(GTSAM's relativeErrorTol)",
       {"base_relative_error_tol"}},
      {"base_absolute_function_tolerance",
       "1e-5",
       "the inner optimizer stops when its error (chi2 / 2) decreases by less than this "
       "(GTSAM's absoluteErrorTol)",
       {"base_absolute_error_tol"}},
  };
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    GtsamGncOptions o;
    const std::string& loss = options.getString("loss");
    if (loss == "tls")
      o.loss = GtsamGncOptions::Loss::kTls;
    else if (loss == "gm")
      o.loss = GtsamGncOptions::Loss::kGm;
    else
      throw Error("gtsam-gnc: option loss must be tls or gm, not '" + loss + "'");
    const std::string& base = options.getString("base");
    if (base == "lm")
      o.base = GtsamGncOptions::Base::kLevenbergMarquardt;
    else if (base == "gn")
      o.base = GtsamGncOptions::Base::kGaussNewton;
    else
      throw Error("gtsam-gnc: option base must be lm or gn, not '" + base + "'");
    o.probability = options.getDouble("probability");
    if (!(o.probability > 0 && o.probability < 1))
      throw Error("gtsam-gnc: option probability must be in (0, 1)");
    o.threshold = options.getDouble("threshold");
    if (!(o.threshold >= 0) || !std::isfinite(o.threshold))
      throw Error("gtsam-gnc: option threshold must be a finite number >= 0 (0: use probability)");
    o.mu_step = options.getDouble("mu_step");
    if (!(o.mu_step > 1) || !std::isfinite(o.mu_step))
      throw Error("gtsam-gnc: option mu_step must be > 1");
    const long iterations = options.getInt("max_iterations");
    if (iterations < 1 || iterations > 100000)
      throw Error("gtsam-gnc: option max_iterations must be in [1, 100000]");
    o.max_iterations = static_cast<int>(iterations);
    o.function_tolerance = options.getDouble("function_tolerance");
    o.weight_tolerance = options.getDouble("weight_tolerance");
    if (!(o.function_tolerance >= 0) || !(o.weight_tolerance >= 0))
      throw Error("gtsam-gnc: options function_tolerance and weight_tolerance must be >= 0");
    const long base_iterations = options.getInt("base_max_iterations");
    if (base_iterations < 1 || base_iterations > 100000)
      throw Error("gtsam-gnc: option base_max_iterations must be in [1, 100000]");
    o.base_max_iterations = static_cast<int>(base_iterations);
    o.base_function_tolerance = options.getDouble("base_function_tolerance");
    o.base_absolute_function_tolerance = options.getDouble("base_absolute_function_tolerance");
    if (!(o.base_function_tolerance >= 0) || !(o.base_absolute_function_tolerance >= 0))
      throw Error(
          "gtsam-gnc: options base_function_tolerance and base_absolute_function_tolerance "
          "must be >= 0");
    return std::make_unique<GtsamGncBackend>(o);
  };
  return info;
}

}  // namespace hamal::gtsam_plugin
