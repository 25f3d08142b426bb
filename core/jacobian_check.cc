// The Jacobian check: see jacobian_check.h.
#include "core/jacobian_check.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/error.h"

namespace hamal {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string describe(const Factor& factor) {
  std::string s = factor.tag() + " (";
  for (std::size_t i = 0; i < factor.keys().size(); ++i)
    s += (i ? ", " : "") + factor.keys()[i].str();
  return s + ")";
}

std::string describe(const Factor& factor, const Values& values) {
  std::ostringstream os;
  os.precision(17);
  for (std::size_t i = 0; i < factor.keys().size(); ++i) {
    const Key k = factor.keys()[i];
    os << (i ? ", " : "") << k << " = [";
    if (values.contains(k)) {
      const int d = values.dim(k);
      for (int j = 0; j < d; ++j) os << (j ? " " : "") << values.data(k)[j];
    }
    os << "]";
  }
  return os.str();
}

// The sampler's state must fit the cost function, or the check would read
// past the ends of parameter blocks.
void checkState(const Factor& factor, const Values& values) {
  const auto& sizes = factor.costFunction()->parameter_block_sizes();
  for (std::size_t i = 0; i < factor.keys().size(); ++i) {
    const Key k = factor.keys()[i];
    if (!values.contains(k))
      throw Error("checkJacobians: the sampler's state has no variable " + k.str() + " of " +
                  describe(factor));
    if (values.dim(k) != sizes[i])
      throw Error("checkJacobians: variable " + k.str() + " has " + std::to_string(values.dim(k)) +
                  " parameters, the cost function of " + describe(factor) + " expects " +
                  std::to_string(sizes[i]));
  }
}

struct Evaluation {
  std::vector<double> residual;
  std::vector<std::vector<double>> jacobians;  // row-major, one per block
};

class Evaluator {
 public:
  Evaluator(const Factor& factor, Values& values) : cost_(*factor.costFunction()) {
    for (Key k : factor.keys()) params_.push_back(values.data(k));
    sizes_ = cost_.parameter_block_sizes();
    m_ = cost_.num_residuals();
  }

  int blocks() const { return static_cast<int>(params_.size()); }
  int size(int block) const { return sizes_[block]; }
  int residuals() const { return m_; }
  double* param(int block) { return params_[block]; }

  // `which`: -1 for every block's Jacobian, -2 for none, else only that block.
  bool evaluate(int which, Evaluation* out) {
    out->residual.assign(m_, 0.0);
    out->jacobians.assign(params_.size(), {});
    std::vector<double*> jac(params_.size(), nullptr);
    for (int b = 0; b < blocks(); ++b) {
      if (which == -1 || which == b) {
        out->jacobians[b].assign(m_ * sizes_[b], 0.0);
        jac[b] = out->jacobians[b].data();
      }
    }
    std::vector<const double*> p(params_.begin(), params_.end());
    const bool ok =
        cost_.Evaluate(p.data(), out->residual.data(), which == -2 ? nullptr : jac.data());
    if (!ok) return false;
    for (double v : out->residual)
      if (!std::isfinite(v)) return false;
    return true;
  }

 private:
  const ceres::CostFunction& cost_;
  std::vector<double*> params_;
  std::vector<int32_t> sizes_;
  int m_ = 0;
};

// Equal, NaN counting as equal to NaN: a NaN entry is reported as the
// worst Jacobian entry, not as an inconsistency between evaluations.
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  return true;
}

double scaledError(double analytic, double numeric) {
  return std::abs(analytic - numeric) / std::max(1.0, std::abs(numeric));
}

}  // namespace

Values::Entry randomEntry(VariableType type, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> position(-10.0, 10.0);
  // (-pi, pi]: the convention of wrapAngle.
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  Values::Entry e{type, {0.0, 0.0, 0.0}};
  e.data[0] = position(rng);
  e.data[1] = position(rng);
  if (type == VariableType::kPose2) {
    double th = angle(rng);
    if (th == -kPi) th = kPi;
    e.data[2] = th;
  }
  return e;
}

Values randomValues(const Factor& factor, std::mt19937_64& rng) {
  const auto& sizes = factor.costFunction()->parameter_block_sizes();
  Values values;
  for (std::size_t i = 0; i < factor.keys().size(); ++i) {
    VariableType type;
    if (sizes[i] == dimension(VariableType::kPose2)) {
      type = VariableType::kPose2;
    } else if (sizes[i] == dimension(VariableType::kPoint2)) {
      type = VariableType::kPoint2;
    } else {
      throw Error("checkJacobians: parameter block " + std::to_string(i) + " of " +
                  describe(factor) + " has size " + std::to_string(sizes[i]) +
                  ", which is no built-in variable type: pass a ValuesSampler");
    }
    // A factor may name one key twice; it is one variable.
    if (!values.contains(factor.keys()[i]))
      values.insertEntry(factor.keys()[i], randomEntry(type, rng));
  }
  return values;
}

JacobianCheckResult checkJacobians(const Factor& factor, const JacobianCheckOptions& options) {
  return checkJacobians(
      factor, [&factor](std::mt19937_64& rng) { return randomValues(factor, rng); }, options);
}

JacobianCheckResult checkJacobians(const Factor& factor, const ValuesSampler& sample,
                                   const JacobianCheckOptions& options) {
  if (options.trials < 1) throw Error("checkJacobians: trials must be at least 1");
  if (!(options.step > 0.0)) throw Error("checkJacobians: step must be positive");
  if (!(options.tolerance > 0.0)) throw Error("checkJacobians: tolerance must be positive");

  JacobianCheckResult result;
  std::mt19937_64 rng(options.seed);
  std::string problem;  // the first failure that is not a tolerance miss
  Values problem_state;
  double worst = -1.0;
  const double h = options.step;

  for (int trial = 0; trial < options.trials && problem.empty(); ++trial) {
    // Draw a state the filter accepts and the cost function can evaluate.
    Values values;
    Evaluation full;
    bool found = false;
    for (int attempt = 0; attempt <= options.max_resamples; ++attempt) {
      values = sample(rng);
      checkState(factor, values);
      if (options.accept && !options.accept(values)) {
        ++result.rejected;
        continue;
      }
      Evaluator ev(factor, values);
      if (!ev.evaluate(-1, &full)) {
        ++result.rejected;
        continue;
      }
      found = true;
      break;
    }
    if (!found) {
      problem = "no acceptable state after " + std::to_string(options.max_resamples + 1) +
                " samples in trial " + std::to_string(trial) +
                " (the filter rejects them or Evaluate fails)";
      break;
    }
    ++result.trials;
    Evaluator ev(factor, values);

    // Ceres asks for some blocks only (constant blocks) or for none: each
    // must give the same numbers as the full evaluation.
    Evaluation part;
    if (!ev.evaluate(-2, &part) || !same(part.residual, full.residual)) {
      problem = "trial " + std::to_string(trial) +
                ": the residual evaluated without Jacobians differs from the residual with them";
      problem_state = values;
      break;
    }
    for (int b = 0; b < ev.blocks() && problem.empty(); ++b) {
      if (!ev.evaluate(b, &part) || !same(part.jacobians[b], full.jacobians[b]))
        problem = "trial " + std::to_string(trial) + ": the Jacobian of block " +
                  std::to_string(b) + " alone differs from the one evaluated with all blocks";
    }
    if (!problem.empty()) {
      problem_state = values;
      break;
    }

    for (int b = 0; b < ev.blocks() && problem.empty(); ++b) {
      for (int c = 0; c < ev.size(b); ++c) {
        double* x = ev.param(b) + c;
        const double x0 = *x;
        Evaluation plus, minus;
        *x = x0 + h;
        const bool ok_plus = ev.evaluate(-2, &plus);
        *x = x0 - h;
        const bool ok_minus = ev.evaluate(-2, &minus);
        *x = x0;
        if (!ok_plus || !ok_minus) {
          problem = "trial " + std::to_string(trial) + ": Evaluate fails within the step " +
                    "of an accepted state (block " + std::to_string(b) + ", parameter " +
                    std::to_string(c) + "): filter such states out with options.accept";
          problem_state = values;
          break;
        }
        for (int r = 0; r < ev.residuals(); ++r) {
          const double numeric = (plus.residual[r] - minus.residual[r]) / (2.0 * h);
          const double analytic = full.jacobians[b][r * ev.size(b) + c];
          const double abs_error = std::abs(analytic - numeric);
          const double scaled = scaledError(analytic, numeric);
          // NaN in the analytic Jacobian must count as the worst error.
          const double key = std::isnan(scaled) ? INFINITY : scaled;
          result.max_abs_error =
              std::max(result.max_abs_error, std::isnan(abs_error) ? INFINITY : abs_error);
          if (key > worst) {
            worst = key;
            result.max_rel_error = key;
            result.worst.trial = trial;
            result.worst.block = b;
            result.worst.row = r;
            result.worst.col = c;
            result.worst.analytic = analytic;
            result.worst.numeric = numeric;
            result.worst.state = values;
          }
        }
      }
    }
  }

  result.ok = problem.empty() && result.trials == options.trials &&
              result.max_rel_error <= options.tolerance;

  std::ostringstream os;
  os << "Jacobian check of " << describe(factor) << ": " << (result.ok ? "OK" : "FAILED") << ", "
     << result.trials << " of " << options.trials << " random states checked (" << result.rejected
     << " resampled), step " << options.step << ", tolerance " << options.tolerance
     << " on |analytic - numeric| / max(1, |numeric|).";
  if (!problem.empty()) os << " Stopped: " << problem << ".";
  if (result.worst.trial >= 0) {
    os.precision(6);
    os << " Worst entry: trial " << result.worst.trial << ", block " << result.worst.block << " ("
       << factor.keys()[result.worst.block] << "), d residual[" << result.worst.row
       << "] / d parameter[" << result.worst.col << "]: analytic " << result.worst.analytic
       << ", numeric " << result.worst.numeric << ", error " << result.max_rel_error
       << " (largest absolute error " << result.max_abs_error << ").";
  }
  if (!problem.empty() && !problem_state.empty())
    os << " State where it stopped: " << describe(factor, problem_state) << ".";
  else if (!result.ok && result.worst.trial >= 0)
    os << " State of the worst entry: " << describe(factor, result.worst.state) << ".";
  result.report = os.str();
  return result;
}

}  // namespace hamal
