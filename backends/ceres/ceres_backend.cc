// CeresBackend: see ceres_backend.h.
#include "backends/ceres/ceres_backend.h"

#include <ceres/covariance.h>

#include <iostream>
#include <string>

#include "core/error.h"
#include "core/finite_result.h"
#include "core/phase_clock.h"

namespace hamal {

std::vector<OptionSpec> CeresBackend::optionSpecs() {
  return {
      {"every", "1", "solve every k-th update (1 = batch re-solve at every step)"},
      {"max_iterations", "100", "Ceres max_num_iterations per solve"},
      {"function_tolerance", "1e-6", "Ceres function_tolerance (relative cost change)"},
      {"gradient_tolerance", "1e-10", "Ceres gradient_tolerance"},
      {"parameter_tolerance", "1e-8", "Ceres parameter_tolerance (relative step size)"},
      {"linear_solver", "sparse_normal_cholesky",
       "sparse_normal_cholesky (SuiteSparse CHOLMOD) | sparse_schur | dense_qr | "
       "dense_normal_cholesky | iterative_schur | cgnr"},
      {"trust_region", "levenberg_marquardt", "levenberg_marquardt | dogleg"},
      {"threads", "1", "Ceres num_threads"},
      {"verbose", "false", "print Ceres' per-iteration progress and full report"},
  };
}

CeresBackend::CeresBackend(const Options& options) {
  every_ = options.getInt("every");
  if (every_ < 1) throw Error("ceres: option every=" + std::to_string(every_) + " must be >= 1");
  ceres::Solver::Options& o = solver_options_;
  o.minimizer_type = ceres::TRUST_REGION;
  o.max_num_iterations = static_cast<int>(options.getInt("max_iterations"));
  if (o.max_num_iterations < 0) throw Error("ceres: option max_iterations must be >= 0");
  o.function_tolerance = options.getDouble("function_tolerance");
  o.gradient_tolerance = options.getDouble("gradient_tolerance");
  o.parameter_tolerance = options.getDouble("parameter_tolerance");
  const std::string& solver =
      options.getChoice("linear_solver", {"sparse_normal_cholesky", "sparse_schur", "dense_qr",
                                          "dense_normal_cholesky", "iterative_schur", "cgnr"});
  if (solver == "sparse_normal_cholesky") o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  if (solver == "sparse_schur") o.linear_solver_type = ceres::SPARSE_SCHUR;
  if (solver == "dense_qr") o.linear_solver_type = ceres::DENSE_QR;
  if (solver == "dense_normal_cholesky") o.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  if (solver == "iterative_schur") o.linear_solver_type = ceres::ITERATIVE_SCHUR;
  if (solver == "cgnr") o.linear_solver_type = ceres::CGNR;
  o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  o.trust_region_strategy_type =
      options.getChoice("trust_region", {"levenberg_marquardt", "dogleg"}) == "dogleg"
          ? ceres::DOGLEG
          : ceres::LEVENBERG_MARQUARDT;
  o.num_threads = static_cast<int>(options.getInt("threads"));
  if (o.num_threads < 1) throw Error("ceres: option threads must be >= 1");
  const bool verbose = options.getBool("verbose");
  o.minimizer_progress_to_stdout = verbose;
  o.logging_type = verbose ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  std::string why;
  if (!o.IsValid(&why)) throw Error("ceres: invalid solver options: " + why);

  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_ = std::make_unique<ceres::Problem>(po);
}

UpdateResult CeresBackend::update(const Step& step) {
  UpdateResult result = solve(step);
  last_status_ = result.status;
  return result;
}

Status CeresBackend::jointMarginalCovariance(const std::vector<Key>& keys,
                                             Eigen::MatrixXd* covariance) {
  Values& estimate = kit_.estimate();
  const long size = checkMarginalKeys(keys, estimate, kit_.name());
  if (!last_status_.ok())
    return Status::numericalFailure(
        "ceres: no marginal covariance: the last update did not end ok (" + last_status_.message +
            ")",
        last_status_.keys);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (std::size_t j = i; j < keys.size(); ++j)
      pairs.emplace_back(estimate.data(keys[i]), estimate.data(keys[j]));
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::SPARSE_QR;
  options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  options.num_threads = solver_options_.num_threads;
  ceres::Covariance ceres_covariance(options);
  if (!ceres_covariance.Compute(pairs, problem_.get()))
    return Status::numericalFailure(
        "ceres: ceres::Covariance could not compute the covariance (the Jacobian is rank "
        "deficient: a direction nothing constrains)",
        keys);
  Eigen::MatrixXd out(size, size);
  std::vector<long> places;
  long place = 0;
  for (Key key : keys) {
    places.push_back(place);
    place += estimate.dim(key);
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (std::size_t j = i; j < keys.size(); ++j) {
      const int di = estimate.dim(keys[i]), dj = estimate.dim(keys[j]);
      RowMajor block(di, dj);
      if (!ceres_covariance.GetCovarianceBlock(estimate.data(keys[i]), estimate.data(keys[j]),
                                               block.data()))
        return Status::numericalFailure(
            "ceres: ceres::Covariance has no block for " + keys[i].str() + ", " + keys[j].str(),
            {keys[i], keys[j]});
      out.block(places[i], places[j], di, dj) = block;
      out.block(places[j], places[i], dj, di) = block.transpose();
    }
  if (!out.allFinite())
    return Status::numericalFailure("ceres: the marginal covariance is not finite", keys);
  *covariance = std::move(out);
  return Status();
}

UpdateResult CeresBackend::solve(const Step& step) {
  PhaseClock clock;
  UpdateResult result;
  kit_.admit(step);
  Values& estimate = kit_.estimate();
  for (const auto& [key, entry] : step.new_values)
    problem_->AddParameterBlock(estimate.data(key), estimate.dim(key));
  // A fixed variable keeps its value: Ceres holds it constant (step.h).
  for (Key key : step.fixed) problem_->SetParameterBlockConstant(estimate.data(key));
  std::vector<double*> blocks;
  for (const FactorPtr& f : step.new_factors) {
    blocks.clear();
    for (Key key : f->keys()) blocks.push_back(estimate.data(key));
    problem_->AddResidualBlock(f->costFunction(), f->lossFunction(), blocks);
  }
  ++updates_;
  result.variables = estimate.size();

  if (updates_ % every_ != 0 || problem_->NumResidualBlocks() == 0) {
    // No solve: the variables keep their guesses, which must be finite for
    // an ok (a protocol composes them from an earlier, failed estimate).
    result.status = finiteEstimateStatus(estimate, kit_.name());
    clock.finish(&result.time);
    return result;
  }

  // Ceres' damped steps solve a graph that nothing anchors as readily as
  // any other, to one of its many optima: say instead what is missing, as
  // every back-end does (core/gauge_freedom.h).
  result.status = kit_.gaugeStatus();
  if (!result.status.ok()) {
    clock.finish(&result.time);
    return result;
  }

  ceres::Solver::Summary summary;
  ceres::Solve(solver_options_, problem_.get(), &summary);
  if (solver_options_.minimizer_progress_to_stdout) std::cout << summary.FullReport() << "\n";
  // Ceres leaves angles unwrapped while it iterates; a fixed variable keeps
  // its value bit for bit, so it is not rewrapped.
  for (const auto& kv : estimate) {
    if (kv.second.type != VariableType::kPose2) continue;
    double* d = estimate.data(kv.first);
    if (!problem_->IsParameterBlockConstant(d)) d[2] = wrapAngle(d[2]);
  }

  result.kind = UpdateKind::kBatch;
  result.reason = "every " + std::to_string(every_);
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result.variables_relinearized = estimate.size();
  result.columns_total = static_cast<std::size_t>(problem_->NumParameters());
  result.columns_recomputed = result.columns_total;
  // Ceres factorises and back-substitutes in one linear-solver call, so the
  // whole linear solve counts as "factor"; "solve" is the rest of the
  // minimiser (step evaluation, trust-region bookkeeping); "order" is the
  // preprocessor, where the program is reduced and ordered.
  result.time.linearize =
      summary.residual_evaluation_time_in_seconds + summary.jacobian_evaluation_time_in_seconds;
  result.time.factor = summary.linear_solver_time_in_seconds;
  result.time.order = summary.preprocessor_time_in_seconds;
  const double rest =
      summary.minimizer_time_in_seconds - result.time.linearize - result.time.factor;
  result.time.solve = rest > 0 ? rest : 0;
  clock.finish(&result.time);

  // Ceres may stop "converged" at an infinite cost (no step lowers it), or
  // at one so large that rounding hides the measurements: its damped steps
  // never meet the singular system a plain factorisation refuses.
  Status finite = kit_.finiteStatus();
  if (finite.ok()) finite = resolvableCostStatus(kit_.factors(), kit_.estimate(), "ceres");
  if (!finite.ok()) {
    result.status = finite;
  } else if (summary.termination_type == ceres::FAILURE || !summary.IsSolutionUsable()) {
    result.status = Status::numericalFailure("ceres: " + summary.message);
  } else if (summary.termination_type == ceres::NO_CONVERGENCE) {
    result.status.code = Status::kNotConverged;
    result.status.message = "ceres: " + summary.message;
  }
  return result;
}

void registerCeresBackend(Registry& registry) {
  BackendInfo info;
  info.name = "ceres";
  info.description =
      "Ceres batch baseline: one growing ceres::Problem solved to convergence every k updates "
      "(Levenberg-Marquardt, SPARSE_NORMAL_CHOLESKY with SuiteSparse, warm-started)";
  info.options = CeresBackend::optionSpecs();
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    return std::make_unique<CeresBackend>(options);
  };
  registry.addBackend(std::move(info));
}

}  // namespace hamal
