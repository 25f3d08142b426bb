// GtsamGncBackend: see gtsam_gnc_backend.h.
#include "gtsam_gnc_backend.h"

#include <gtsam/nonlinear/GaussNewtonOptimizer.h>
#include <gtsam/nonlinear/GncOptimizer.h>
#include <gtsam/nonlinear/LevenbergMarquardtOptimizer.h>

#include <cmath>
#include <string>

#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "core/finite_result.h"
#include "core/stopwatch.h"
#include "gtsam_factor_adapter.h"

namespace hamal::gtsam_plugin {

namespace {

constexpr const char* kName = "gtsam-gnc";

template <class BaseParams>
gtsam::Values runGnc(const gtsam::NonlinearFactorGraph& graph, const gtsam::Values& initial,
                     BaseParams base, const GtsamGncOptions& o,
                     const gtsam::FastVector<uint64_t>& known_inliers,
                     std::vector<double>* weights) {
  base.maxIterations = o.base_max_iterations;
  base.relativeErrorTol = o.base_relative_error_tol;
  base.absoluteErrorTol = o.base_absolute_error_tol;
  gtsam::GncParams<BaseParams> params(base);
  params.setLossType(o.loss == GtsamGncOptions::Loss::kTls ? gtsam::GncLossType::TLS
                                                           : gtsam::GncLossType::GM);
  params.setMaxIterations(static_cast<std::size_t>(o.max_iterations));
  params.setMuStep(o.mu_step);
  params.setRelativeCostTol(o.relative_cost_tol);
  params.setWeightsTol(o.weights_tol);
  params.setKnownInliers(known_inliers);
  gtsam::GncOptimizer<gtsam::GncParams<BaseParams>> gnc(graph, initial, params);
  gnc.setInlierCostThresholdsAtProbability(o.probability);
  gtsam::Values result = gnc.optimize();
  const gtsam::Vector& w = gnc.getWeights();
  weights->assign(w.data(), w.data() + w.size());
  return result;
}

}  // namespace

UpdateResult GtsamGncBackend::update(const Step& step) {
  UpdateResult result;
  result.kind = UpdateKind::kBatch;
  result.reason = "GTSAM GncOptimizer over the whole graph";
  Stopwatch phase;

  // Everything that can refuse the step runs before anything is recorded.
  checkStep(step, estimate_, kName);
  gtsam::NonlinearFactorGraph factors = toGtsamFactors(step.new_factors, kName);
  const std::size_t mapped = factors.size();
  const std::vector<Key> newly_fixed = addFixedPriors(step, estimate_, fixed_set_, &factors);

  for (const auto& [key, entry] : step.new_values) {
    estimate_.insertEntry(key, entry);
    insertGtsamValue(key, entry, &values_);
    columns_total_ += dimension(entry.type);
  }
  graph_.push_back(factors.begin(), factors.end());
  for (std::size_t i = 0; i < factors.size(); ++i) {
    owner_.push_back(i < mapped ? step.new_factors[i] : nullptr);
    candidate_.push_back(i < mapped && robust::isLoopClosure(*step.new_factors[i]));
  }
  weights_.resize(graph_.size(), 1.0);
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

  gtsam::FastVector<uint64_t> known_inliers;
  for (std::size_t i = 0; i < graph_.size(); ++i)
    if (!candidate_[i]) known_inliers.push_back(i);
  try {
    if (options_.base == GtsamGncOptions::Base::kLevenbergMarquardt) {
      gtsam::LevenbergMarquardtParams base;
      base.setVerbosityLM("SILENT");
      values_ = runGnc(graph_, values_, base, options_, known_inliers, &weights_);
    } else {
      values_ =
          runGnc(graph_, values_, gtsam::GaussNewtonParams(), options_, known_inliers, &weights_);
    }
  } catch (...) {
    result.time.solve = phase.lap();
    result.status = gtsamFailure(kName);
    return result;
  }
  result.time.solve = phase.lap();
  copyFromGtsam(values_, fixed_, &estimate_);
  result.time.estimate = phase.lap();
  result.variables_relinearized = estimate_.size();
  result.status = finiteEstimateStatus(estimate_, kName);
  result.time.other += phase.lap();
  return result;
}

std::vector<InlierDecisions::Decision> GtsamGncBackend::inlierDecisions() const {
  const double level = options_.loss == GtsamGncOptions::Loss::kTls ? 0.5 : 0.25;
  std::vector<Decision> out;
  for (std::size_t i = 0; i < graph_.size(); ++i)
    if (candidate_[i]) out.push_back({owner_[i].get(), weights_[i], weights_[i] < level});
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
      {"mu_step", "1.4", "factor of each mu update, > 1"},
      {"max_iterations", "100", "GNC's outer iterations, at most (>= 1)"},
      {"relative_cost_tol", "1e-5", "GNC stops when the weighted cost changes less (relative)"},
      {"weights_tol", "1e-4", "GNC-TLS stops when every weight is this close to 0 or 1"},
      {"base_max_iterations", "100", "the inner optimizer's iterations, at most (>= 1)"},
      {"base_relative_error_tol", "1e-5", "the inner optimizer's relative error tolerance"},
      {"base_absolute_error_tol", "1e-5", "the inner optimizer's absolute error tolerance"},
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
    o.mu_step = options.getDouble("mu_step");
    if (!(o.mu_step > 1) || !std::isfinite(o.mu_step))
      throw Error("gtsam-gnc: option mu_step must be > 1");
    const long iterations = options.getInt("max_iterations");
    if (iterations < 1 || iterations > 100000)
      throw Error("gtsam-gnc: option max_iterations must be in [1, 100000]");
    o.max_iterations = static_cast<int>(iterations);
    o.relative_cost_tol = options.getDouble("relative_cost_tol");
    o.weights_tol = options.getDouble("weights_tol");
    if (!(o.relative_cost_tol >= 0) || !(o.weights_tol >= 0))
      throw Error("gtsam-gnc: options relative_cost_tol and weights_tol must be >= 0");
    const long base_iterations = options.getInt("base_max_iterations");
    if (base_iterations < 1 || base_iterations > 100000)
      throw Error("gtsam-gnc: option base_max_iterations must be in [1, 100000]");
    o.base_max_iterations = static_cast<int>(base_iterations);
    o.base_relative_error_tol = options.getDouble("base_relative_error_tol");
    o.base_absolute_error_tol = options.getDouble("base_absolute_error_tol");
    if (!(o.base_relative_error_tol >= 0) || !(o.base_absolute_error_tol >= 0))
      throw Error("gtsam-gnc: the inner optimizer's error tolerances must be >= 0");
    return std::make_unique<GtsamGncBackend>(o);
  };
  return info;
}

}  // namespace hamal::gtsam_plugin
