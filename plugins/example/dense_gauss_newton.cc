// DenseGaussNewton: see dense_gauss_newton.h.
#include "plugins/example/dense_gauss_newton.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/linearization.h"
#include "core/stopwatch.h"

namespace hamal::example {

namespace {
// A pivot this much smaller than the largest is treated as zero: the
// system is singular (an unanchored graph) and its solution meaningless.
constexpr double kRelativePivotTolerance = 1e-12;
// Beyond this the dense matrix alone would take gigabytes.
constexpr int kMaxDimension = 12000;
}  // namespace

DenseGaussNewton::DenseGaussNewton(int max_iterations, double tolerance)
    : max_iterations_(max_iterations), tolerance_(tolerance) {}

UpdateResult DenseGaussNewton::update(const Step& step) {
  UpdateResult result;
  result.kind = UpdateKind::kBatch;
  result.reason = "dense Gauss-Newton re-solves every step";
  Stopwatch other;

  checkStep(step, estimate_, "dense-gauss-newton");
  for (const auto& [key, entry] : step.new_values) {
    estimate_.insertEntry(key, entry);
    variables_.push_back(key);
  }
  // A fixed variable keeps its value and has no column (core/step.h): the
  // columns are laid out again over the free variables.
  fixed_.insert(step.fixed.begin(), step.fixed.end());
  offset_.clear();
  dimension_ = 0;
  for (Key k : variables_) {
    if (fixed_.count(k)) continue;
    offset_[k] = dimension_;
    dimension_ += estimate_.dim(k);
  }
  for (const auto& f : step.new_factors) factors_.push_back(f);
  result.variables = estimate_.size();
  result.columns_total = dimension_;
  if (dimension_ > kMaxDimension) {
    result.status.code = Status::kInvalidInput;
    result.status.message = "dense-gauss-newton handles at most " + std::to_string(kMaxDimension) +
                            " scalar variables, the graph has " + std::to_string(dimension_);
    return result;
  }
  result.time.other += other.seconds();

  const int n = dimension_;
  if (n == 0) {  // every variable fixed (or none yet): nothing to solve
    result.kind = UpdateKind::kNone;
    result.reason = "no free variable";
    return result;
  }
  Eigen::MatrixXd hessian(n, n);
  Eigen::VectorXd gradient(n);
  Linearization lin;
  std::vector<const double*> params;
  for (int iteration = 0; iteration < max_iterations_; ++iteration) {
    Stopwatch phase;
    hessian.setZero();
    gradient.setZero();
    for (const auto& f : factors_) {
      const auto& keys = f->keys();
      params.clear();
      for (Key k : keys) params.push_back(estimate_.data(k));
      if (!linearize(*f, params.data(), &lin)) {
        result.status =
            Status::numericalFailure("a factor's residual or Jacobian is not finite", keys);
        return result;
      }
      for (std::size_t i = 0; i < keys.size(); ++i) {
        const auto oi = offset_.find(keys[i]);
        if (oi == offset_.end()) continue;  // fixed
        const auto& ji = lin.jacobians[i];
        gradient.segment(oi->second, ji.cols()).noalias() += ji.transpose() * lin.residual;
        for (std::size_t j = 0; j < keys.size(); ++j) {
          const auto oj = offset_.find(keys[j]);
          if (oj == offset_.end()) continue;
          const auto& jj = lin.jacobians[j];
          hessian.block(oi->second, oj->second, ji.cols(), jj.cols()).noalias() +=
              ji.transpose() * jj;
        }
      }
    }
    result.time.linearize += phase.lap();

    Eigen::LDLT<Eigen::MatrixXd> ldlt(hessian);
    result.time.factor += phase.lap();
    result.columns_recomputed += n;
    if (ldlt.info() != Eigen::Success) {
      result.status = Status::numericalFailure("LDLT of the normal equations failed");
      return result;
    }
    const Eigen::VectorXd d = ldlt.vectorD();
    const double largest = d.cwiseAbs().maxCoeff();
    for (int i = 0; i < n; ++i) {
      if (std::isfinite(d(i)) && d(i) > kRelativePivotTolerance * largest) continue;
      // Pivot i of P A P^T is column (P * [0..n-1])_i of A.
      const Eigen::VectorXd index =
          ldlt.transpositionsP() * Eigen::VectorXd::LinSpaced(n, 0, n - 1);
      const int column = static_cast<int>(index(i));
      Key culprit = variables_.front();
      for (Key k : variables_) {  // free variables' columns grow in this order
        const auto o = offset_.find(k);
        if (o != offset_.end() && o->second <= column) culprit = k;
      }
      result.status = Status::numericalFailure(
          "the normal equations are singular or indefinite (LDLT pivot " + std::to_string(d(i)) +
              " at variable " + culprit.str() + "); is the graph anchored by a prior?",
          {culprit});
      return result;
    }
    const Eigen::VectorXd dx = ldlt.solve(-gradient);
    result.time.solve += phase.lap();
    if (!dx.allFinite()) {
      result.status = Status::numericalFailure("the Gauss-Newton step is not finite");
      return result;
    }
    for (const auto& [k, offset] : offset_) estimate_.retract(k, dx.data() + offset);
    result.time.other += phase.lap();
    ++result.iterations;
    if (dx.lpNorm<Eigen::Infinity>() < tolerance_) break;
  }
  result.variables_relinearized = result.variables;
  return result;
}

BackendInfo denseGaussNewtonInfo() {
  BackendInfo info;
  info.name = "dense-gauss-newton";
  info.description =
      "example plugin: Gauss-Newton on the dense normal equations (Eigen LDLT), re-solved every "
      "step; for graphs of a few hundred variables";
  info.options = {
      {"max_iterations", "20", "Gauss-Newton iterations per update, at most (>= 1)"},
      {"tolerance", "1e-6", "stop once the largest |dx| of an iteration is below this"},
  };
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    const long iterations = options.getInt("max_iterations");
    const double tolerance = options.getDouble("tolerance");
    if (iterations < 1)
      throw Error("dense-gauss-newton: option max_iterations=" + std::to_string(iterations) +
                  " must be at least 1");
    if (!(tolerance >= 0.0)) throw Error("dense-gauss-newton: option tolerance must be >= 0");
    return std::make_unique<DenseGaussNewton>(static_cast<int>(iterations), tolerance);
  };
  return info;
}

}  // namespace hamal::example
