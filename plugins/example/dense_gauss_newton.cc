// DenseGaussNewton: see dense_gauss_newton.h.
#include "dense_gauss_newton.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/linearization.h"
#include "core/metrics.h"
#include "core/phase_clock.h"

namespace hamal::example {

namespace {
// A pivot this much smaller than the largest is treated as zero: the
// system is singular (an unanchored graph) and its solution meaningless.
constexpr double kRelativePivotTolerance = 1e-12;
// A rise of chi2 within this (relative, or absolute at an exact fit) is
// rounding at the optimum, not an overshoot.
constexpr double kRoundingRise = 1e-9;
std::string shortest(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}
// Beyond this the dense matrix alone would take gigabytes.
constexpr int kMaxDimension = 12000;
}  // namespace

DenseGaussNewton::DenseGaussNewton(int max_iterations, double tolerance)
    : max_iterations_(max_iterations), tolerance_(tolerance) {}

UpdateResult DenseGaussNewton::update(const Step& step) {
  PhaseClock clock;
  UpdateResult result;
  result.kind = UpdateKind::kBatch;
  result.reason = "dense Gauss-Newton re-solves every step";
  kit_.admit(step, [this](const Step& s) {
    const long after = kit_.layout().dimensionAfter(s);
    if (after > kMaxDimension)
      throw Error("dense-gauss-newton: step " + std::to_string(s.index) + " would make " +
                  std::to_string(after) + " scalar variables; it handles at most " +
                  std::to_string(kMaxDimension));
  });
  const VariableLayout& layout = kit_.layout();
  const int n = static_cast<int>(layout.dimension());
  result.variables = kit_.estimate().size();
  result.columns_total = n;
  clock.lap(&result.time.other);
  if (n == 0) {  // every variable fixed (or none yet): nothing to solve
    result.kind = UpdateKind::kNone;
    result.reason = "no free variable";
    return result;
  }

  Eigen::MatrixXd hessian(n, n);
  Eigen::VectorXd gradient(n);
  Linearization lin;
  std::vector<const double*> params;
  std::vector<int> vars;
  // ok means converged: the last step below the tolerance, and a cost (with
  // the robust losses) no higher than where the update started (plain
  // Gauss-Newton can overshoot).
  const double start = robustCost(kit_.factors(), kit_.estimate());
  bool converged = false;
  double last_step = 0;
  for (int iteration = 0; iteration < max_iterations_; ++iteration) {
    hessian.setZero();
    gradient.setZero();
    for (const auto& f : kit_.factors()) {
      const auto& keys = f->keys();
      params.clear();
      vars.clear();
      for (Key k : keys) {
        params.push_back(kit_.estimate().data(k));
        vars.push_back(layout.index(k));
      }
      if (!linearize(*f, params.data(), &lin)) {
        result.status =
            Status::numericalFailure("a factor's residual or Jacobian is not finite", keys);
        clock.finish(&result.time);
        return result;
      }
      for (std::size_t i = 0; i < keys.size(); ++i) {
        if (layout.fixed(vars[i])) continue;
        const long ci = layout.column(vars[i]);
        const auto& ji = lin.jacobians[i];
        gradient.segment(ci, ji.cols()).noalias() += ji.transpose() * lin.residual;
        for (std::size_t j = 0; j < keys.size(); ++j) {
          if (layout.fixed(vars[j])) continue;
          const auto& jj = lin.jacobians[j];
          hessian.block(ci, layout.column(vars[j]), ji.cols(), jj.cols()).noalias() +=
              ji.transpose() * jj;
        }
      }
    }
    clock.lap(&result.time.linearize);

    Eigen::LDLT<Eigen::MatrixXd> ldlt(hessian);
    clock.lap(&result.time.factor);
    result.columns_recomputed += n;
    if (ldlt.info() != Eigen::Success) {
      result.status = Status::numericalFailure("LDLT of the normal equations failed");
      clock.finish(&result.time);
      return result;
    }
    const Eigen::VectorXd d = ldlt.vectorD();
    const double largest = d.cwiseAbs().maxCoeff();
    for (int i = 0; i < n; ++i) {
      if (std::isfinite(d(i)) && d(i) > kRelativePivotTolerance * largest) continue;
      // Pivot i of P A P^T is column (P * [0..n-1])_i of A.
      const Eigen::VectorXd index =
          ldlt.transpositionsP() * Eigen::VectorXd::LinSpaced(n, 0, n - 1);
      const Key culprit = layout.key(layout.variableOfColumn(static_cast<long>(index(i))));
      result.status = Status::numericalFailure(
          "the normal equations are singular or indefinite (LDLT pivot " + std::to_string(d(i)) +
              " at variable " + culprit.str() + "); is the graph anchored by a prior?",
          {culprit});
      clock.finish(&result.time);
      return result;
    }
    const Eigen::VectorXd dx = ldlt.solve(-gradient);
    clock.lap(&result.time.solve);
    if (!dx.allFinite()) {
      result.status = Status::numericalFailure("the Gauss-Newton step is not finite");
      clock.finish(&result.time);
      return result;
    }
    kit_.retract(dx.data());
    ++result.iterations;
    last_step = dx.lpNorm<Eigen::Infinity>();
    if (last_step < tolerance_) {
      converged = true;
      break;
    }
  }
  result.variables_relinearized = result.variables;
  result.status = kit_.finiteStatus();
  if (result.status.ok()) {
    const double end = robustCost(kit_.factors(), kit_.estimate());
    if (!converged || !(end <= start * (1 + kRoundingRise) + kRoundingRise)) {
      result.status.code = Status::kNotConverged;
      result.status.message =
          !converged
              ? "dense-gauss-newton: the largest |dx| is still " + shortest(last_step) + " after " +
                    std::to_string(max_iterations_) + " iterations (max_iterations)"
              : "dense-gauss-newton: the cost rose from " + shortest(start) + " to " +
                    shortest(end);
    }
  }
  clock.finish(&result.time);
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
