// Isam2Backend: see isam2_backend.h.
#include "isam2_backend.h"

#include <gtsam/geometry/Point2.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/inference/Symbol.h>

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/stopwatch.h"
#include "gtsam_factor_adapter.h"

namespace hamal::gtsam_plugin {

namespace {

constexpr const char* kName = "isam2";

gtsam::ISAM2Params makeParams(const Isam2Options& o) {
  gtsam::ISAM2Params params;
  params.relinearizeThreshold = o.relinearize_threshold;
  params.relinearizeSkip = o.relinearize_skip;
  if (o.dogleg) {
    gtsam::ISAM2DoglegParams dogleg;
    dogleg.wildfireThreshold = o.wildfire_threshold;
    params.optimizationParams = dogleg;
  } else {
    params.optimizationParams = gtsam::ISAM2GaussNewtonParams(o.wildfire_threshold);
  }
  return params;
}

}  // namespace

Isam2Backend::Isam2Backend(const Isam2Options& options) : isam_(makeParams(options)) {}

UpdateResult Isam2Backend::update(const Step& step) {
  UpdateResult result;
  result.kind = UpdateKind::kIncremental;
  Stopwatch phase;

  // Everything that can refuse the step runs before anything is recorded.
  checkStep(step, estimate_, kName);
  gtsam::NonlinearFactorGraph factors = toGtsamFactors(step.new_factors, kName);
  gtsam::Values values;
  for (const auto& [key, entry] : step.new_values) insertGtsamValue(key, entry, &values);
  const std::vector<Key> newly_fixed = addFixedPriors(step, estimate_, fixed_set_, &factors);

  for (const auto& [key, entry] : step.new_values) {
    estimate_.insertEntry(key, entry);
    const int d = dimension(entry.type);
    if (dimension_ == 0) dimension_ = d;
    uniform_dimension_ = uniform_dimension_ && d == dimension_;
    columns_total_ += d;
  }
  for (Key k : newly_fixed) {
    fixed_.push_back(k);
    fixed_set_.insert(k);
  }
  result.variables = estimate_.size();
  result.columns_total = columns_total_;
  result.time.other = phase.lap();

  gtsam::ISAM2Result r;
  try {
    r = isam_.update(factors, values);
  } catch (...) {
    result.time.factor = phase.lap();
    result.status = gtsamFailure(kName);
    return result;
  }
  result.time.factor = phase.lap();

  result.status = refreshEstimate();
  result.time.estimate = phase.lap();
  if (!result.status.ok()) return result;

  result.iterations = 1;  // iSAM2 takes one Gauss-Newton (or dogleg) step per update
  result.variables_relinearized = r.variablesRelinearized;
  // Exact while all variables share one dimension (see isam2_backend.h).
  result.columns_recomputed = r.variablesReeliminated * std::size_t(dimension_);
  result.reason = "iSAM2: " + std::to_string(r.variablesRelinearized) + " relinearised, " +
                  std::to_string(r.variablesReeliminated) + " re-eliminated, " +
                  std::to_string(r.factorsRecalculated) + " factors recalculated, " +
                  std::to_string(r.cliques) + " cliques" +
                  (uniform_dimension_ ? "" : " (columns counted at the first variable's dim)");
  result.time.other += phase.lap();
  return result;
}

// What ISAM2::calculateEstimate() computes, theta retracted by delta, written
// straight into hamal's values instead of into a new gtsam::Values (one node
// allocation per variable and step), and checked for finiteness on the way.
// getDelta() runs iSAM2's wildfire back-substitution when it is stale.
Status Isam2Backend::refreshEstimate() {
  const gtsam::VectorValues* delta = nullptr;
  try {
    delta = &isam_.getDelta();
  } catch (const gtsam::IndeterminantLinearSystemException& e) {
    const Key near = fromGtsam(e.nearbyVariable());
    return Status::numericalFailure(
        std::string(kName) + ": GTSAM found the system indeterminant near " + near.str(), {near});
  }
  const gtsam::Values& theta = isam_.getLinearizationPoint();
  // Both are ordered by key and hold the same variables; a look-up where not.
  auto d = delta->begin();
  for (const auto& kv : theta) {
    if (d == delta->end() || d->first != kv.key) d = delta->find(kv.key);
    if (d == delta->end())
      return Status::numericalFailure(std::string(kName) + ": GTSAM has no delta for " +
                                      fromGtsam(kv.key).str());
    const gtsam::Vector& dx = (d++)->second;
    const Key key = fromGtsam(kv.key);
    if (!fixed_set_.empty() && fixed_set_.count(key)) continue;
    double* out = estimate_.data(key);
    if (dx.size() == 3) {
      const gtsam::Pose2 p = kv.value.cast<gtsam::Pose2>().retract(dx);
      out[0] = p.x();
      out[1] = p.y();
      out[2] = p.theta();
    } else {
      const gtsam::Point2 p = kv.value.cast<gtsam::Point2>() + dx;
      out[0] = p.x();
      out[1] = p.y();
    }
    for (int k = 0; k < int(dx.size()); ++k)
      if (!std::isfinite(out[k]))
        return Status::numericalFailure(
            std::string(kName) + ": the estimate of " + key.str() + " is not finite", {key});
  }
  return Status();
}

BackendInfo isam2Info() {
  BackendInfo info;
  info.name = kName;
  info.description =
      "GTSAM's iSAM2 (GTSAM plugin): Bayes-tree incremental smoothing, one ISAM2::update and "
      "calculateEstimate per step; factors mapped to GTSAM's with hamal's objective";
  info.options = {
      {"relinearize_threshold", "0.1",
       "relinearise a variable whose delta exceeds this (ISAM2Params::relinearizeThreshold, > 0)"},
      {"relinearize_skip", "10",
       "consider relinearising only every this many updates (ISAM2Params::relinearizeSkip, >= 1)"},
      {"optimizer", "gauss-newton",
       "gauss-newton (ISAM2GaussNewtonParams) or dogleg (ISAM2DoglegParams, initial delta 1)"},
      {"wildfire_threshold", "0.001",
       "back-substitution stops where a variable's delta changes less than this (GTSAM's "
       "Gauss-Newton default; its Dogleg default is 1e-5)"},
  };
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    Isam2Options o;
    o.relinearize_threshold = options.getDouble("relinearize_threshold");
    const long skip = options.getInt("relinearize_skip");
    o.dogleg = options.getChoice("optimizer", {"gauss-newton", "dogleg"}) == "dogleg";
    o.wildfire_threshold = options.getDouble("wildfire_threshold");
    if (!(o.relinearize_threshold > 0.0))
      throw Error("isam2: option relinearize_threshold must be positive");
    if (skip < 1) throw Error("isam2: option relinearize_skip must be at least 1");
    if (!(o.wildfire_threshold >= 0.0))
      throw Error("isam2: option wildfire_threshold must be >= 0");
    o.relinearize_skip = static_cast<int>(skip);
    return std::make_unique<Isam2Backend>(o);
  };
  return info;
}

}  // namespace hamal::gtsam_plugin
