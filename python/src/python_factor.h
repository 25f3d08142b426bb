// PythonFactor: a factor whose whitened residual and Jacobians come from a
// Python callable, as GTSAM's CustomFactor (python/README.md, "Factors
// written in Python"). It is an ordinary hamal::Factor: its
// ceres::CostFunction calls the callable with the GIL taken, so Ceres,
// cholesky and AprilSAM evaluate it exactly as they evaluate a C++ factor
// (core/factor.h), in the same run.
//
// The callable gets a list of 1-D float64 arrays (one per key, the
// parameter block as the cost function sees it: a pose's angle is not
// wrapped) and returns (residual, [J_0, J_1, ...]): the whitened residual of
// residual_dim entries and one residual_dim x dim_k Jacobian per key.
// A callable that raises or returns the wrong shapes makes Evaluate return
// false, as a C++ cost function that cannot evaluate does; the reason is
// kept (lastError) so the binding can raise it or append it to a Status.
// What a callable is given is its own: the arrays and predict's Values are
// copies, valid as long as Python holds them.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/factor.h"
#include "core/variable_prediction.h"

namespace hamal::python {

class PythonCostFunction : public ceres::CostFunction {
 public:
  PythonCostFunction(pybind11::function function, int residual_dim, const std::vector<int>& dims,
                     std::string name);
  ~PythonCostFunction() override;

  bool Evaluate(const double* const* parameters, double* residuals,
                double** jacobians) const override;

  // Why the last Evaluate failed ("" when it did not).
  std::string lastError() const;
  std::uint64_t failures() const;

 private:
  pybind11::function* function_;  // released with the GIL held (see the destructor)
  std::string name_;
  mutable std::mutex mutex_;
  mutable std::string last_error_;
  mutable std::uint64_t failures_ = 0;
};

class PythonFactor : public Factor, public VariablePrediction {
 public:
  // `predict` (optional, None for none): predict(unknown_key, known_values)
  // returns a guess for that key (a Pose2 or a 2-vector) or None, so the
  // thesis protocol can initialise a variable from this factor (VariablePrediction::predict).
  // known_values is a new Values with the known variables among the
  // factor's keys (O(keys), not the whole estimate, and the callable may keep it).
  PythonFactor(std::vector<Key> keys, int residual_dim, pybind11::function function,
               const std::vector<int>& dims, std::string name, pybind11::object predict);
  ~PythonFactor() override;

  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  // Not writable: a file cannot hold Python code. Writers refuse a graph
  // with one before writing anything (graph_bindings.cc).
  std::string tag() const override { return "PYTHON_FACTOR"; }
  void writeFields(std::ostream& os) const override;

  const std::string& name() const { return name_; }
  const PythonCostFunction& python() const {
    return static_cast<const PythonCostFunction&>(*costFunction());
  }
  // Evaluates once, with Jacobians, at the variables of `values` or, for
  // those it lacks, of `more`; throws hamal::Error with the factor's name
  // and the callable's error when that fails. Backend.update calls this
  // before the back-end records the factor (with the step's new values and
  // the back-end's estimate, neither copied), so a broken callable is an
  // exception and the back-end stays as it was.
  void check(const Values& values, const Values& more = Values()) const;

 private:
  std::string name_;
  pybind11::object* predict_;  // released with the GIL held, as PythonCostFunction's callable
};

// True on a thread that is running a PythonFactor's callable (function or
// predict) or releasing one: a back-end handle refuses a call from there
// while its own update runs Python code (backend_handle.h).
bool insidePythonCallback();

// The failures of every PythonCostFunction so far, and the last reason:
// the binding of Backend.update appends it to a non-ok Status.
std::uint64_t pythonFactorFailures();
std::string lastPythonFactorError();

}  // namespace hamal::python
