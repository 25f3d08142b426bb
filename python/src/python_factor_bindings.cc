// hamal.PythonFactor and hamal.check_jacobians (python_factor.h,
// core/jacobian_check.h): a factor prototyped in Python is checked with the
// same public checker a C++ factor's author uses.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "core/error.h"
#include "core/jacobian_check.h"
#include "python_factor.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

std::shared_ptr<PythonFactor> makePythonFactor(py::handle keys_arg, int residual_dim,
                                               py::handle function, py::object dims_arg,
                                               const std::string& name, py::object predict) {
  if (!py::isinstance<py::sequence>(keys_arg) || py::isinstance<py::str>(keys_arg))
    throw Error("keys: expected a list of hamal.Key");
  std::vector<Key> keys;
  for (py::handle k : keys_arg) {
    if (!py::isinstance<Key>(k))
      throw Error("keys: expected hamal.Key entries (hamal.x(i), hamal.l(j)), got " +
                  std::string(py::str(py::type::of(k).attr("__name__"))));
    keys.push_back(k.cast<Key>());
  }
  if (keys.empty()) throw Error("keys: a factor needs at least one key");
  if (residual_dim < 1)
    throw Error("residual_dim: must be >= 1, got " + std::to_string(residual_dim));
  if (!PyCallable_Check(function.ptr())) throw Error("function: is not callable");
  std::vector<int> dims;
  if (dims_arg.is_none()) {
    for (Key k : keys) {
      if (k.kind() == kPoseKind)
        dims.push_back(3);
      else if (k.kind() == kLandmarkKind)
        dims.push_back(2);
      else
        throw Error("dims: key " + k.str() + " is neither a pose nor a landmark; give dims");
    }
  } else {
    dims = dims_arg.cast<std::vector<int>>();
    if (dims.size() != keys.size())
      throw Error("dims: " + std::to_string(dims.size()) + " entries for " +
                  std::to_string(keys.size()) + " keys");
    for (int d : dims)
      if (d < 1) throw Error("dims: every entry must be >= 1");
  }
  if (!predict.is_none() && !PyCallable_Check(predict.ptr()))
    throw Error("predict: is not callable");
  return std::make_shared<PythonFactor>(
      keys, residual_dim, py::reinterpret_borrow<py::function>(function), dims, name, predict);
}

// check_jacobians' result, with why a Python factor's function failed.
struct PythonJacobianCheckResult : JacobianCheckResult {
  std::string python_error;
};

// The first line of a PythonCostFunction's reason ("name: the callable
// raised KeyError: 'x'"), without pybind11's traceback lines.
std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

}  // namespace

void bindPythonFactor(py::module_& m) {
  py::class_<PythonFactor, Factor, std::shared_ptr<PythonFactor>>(
      m, "PythonFactor",
      "A factor written in Python (as GTSAM's CustomFactor): function(x) gets one float64 array "
      "per key\n"
      "and returns (whitened residual, [Jacobian per key]); used by every back-end like a C++ "
      "factor.\n"
      "Optional predict(unknown_key, known_values) -> Pose2, 2-vector or None lets the thesis\n"
      "protocol initialise a variable from it.")
      .def(py::init(&makePythonFactor), py::arg("keys"), py::arg("residual_dim"),
           py::arg("function"), py::arg("dims") = py::none(), py::arg("name") = "PythonFactor",
           py::arg("predict") = py::none(),
           "PythonFactor(keys, residual_dim, function, dims=None, name='PythonFactor', "
           "predict=None): dims is each key's variable dimension (default 3 for x(i), 2 for "
           "l(j)); name appears in errors.")
      .def_property_readonly("name", &PythonFactor::name, "The name given (in error messages).")
      .def_property_readonly(
          "failures", [](const PythonFactor& f) { return f.python().failures(); },
          "How many evaluations failed (the callable raised or returned wrong shapes).")
      .def_property_readonly(
          "last_error", [](const PythonFactor& f) { return f.python().lastError(); },
          "Why the last failed evaluation failed, with the Python traceback ('' if none did).")
      .def(
          "check", [](const PythonFactor& f, const Values& v) { f.check(v); }, py::arg("values"),
          "Evaluates once at `values`; hamal.Error naming the reason when the callable fails.")
      .def("__repr__", [](const PythonFactor& f) {
        std::string keys;
        for (Key k : f.keys()) keys += (keys.empty() ? "" : ", ") + k.str();
        return "<hamal.PythonFactor " + f.name() + " on " + keys + ">";
      });

  using R = PythonJacobianCheckResult;
  py::class_<R>(m, "JacobianCheckResult",
                "What check_jacobians found (core/jacobian_check.h); bool(result) is result.ok.")
      .def_readonly("ok", &R::ok, "True when every entry of every Jacobian is within tolerance.")
      .def_readonly("trials", &R::trials, "Random states checked.")
      .def_readonly("rejected", &R::rejected,
                    "States resampled (the accept filter refused them, or the factor could not "
                    "be evaluated there).")
      .def_readonly("max_abs_error", &R::max_abs_error,
                    "max |analytic - numeric| over every entry.")
      .def_readonly("max_rel_error", &R::max_rel_error,
                    "max |analytic - numeric| / max(1, |numeric|): what the tolerance applies to.")
      .def_property_readonly(
          "worst_block", [](const R& r) { return r.worst.block; },
          "The key (index into factor.keys) of the worst entry; -1 if none checked.")
      .def_property_readonly(
          "worst_row", [](const R& r) { return r.worst.row; },
          "The residual row of the worst entry (or -1).")
      .def_property_readonly(
          "worst_col", [](const R& r) { return r.worst.col; },
          "The column within the key's block of the worst entry (or -1).")
      .def_property_readonly(
          "worst_analytic", [](const R& r) { return r.worst.analytic; },
          "The factor's own Jacobian entry at the worst entry.")
      .def_property_readonly(
          "worst_numeric", [](const R& r) { return r.worst.numeric; },
          "The central difference at the worst entry.")
      .def_property_readonly(
          "worst_state", [](const R& r) { return r.worst.state; }, "The Values of the worst trial.")
      .def_readonly("report", &R::report,
                    "One readable paragraph (with a Python factor's exception when it raised).")
      .def_readonly("python_error", &R::python_error,
                    "str: for a PythonFactor whose function failed during the check, the exception "
                    "type and message ('KeyError: ...'); '' otherwise.")
      .def("__bool__", [](const R& r) { return r.ok; })
      .def("__repr__", [](const R& r) { return "<hamal.JacobianCheckResult " + r.report + ">"; });

  m.def(
      "check_jacobians",
      [](const Factor& factor, int trials, double step, double tolerance, std::uint64_t seed,
         std::function<bool(const Values&)> accept) {
        JacobianCheckOptions o;
        o.trials = trials;
        o.step = step;
        o.tolerance = tolerance;
        o.seed = seed;
        if (accept) o.accept = accept;
        const auto* python = dynamic_cast<const PythonFactor*>(&factor);
        const std::uint64_t failures_before = python ? python->python().failures() : 0;
        R out;
        static_cast<JacobianCheckResult&>(out) = checkJacobians(factor, o);
        if (python && python->python().failures() != failures_before) {
          // "name: the callable raised KeyError: 'x'" -> "KeyError: 'x'"
          std::string e = firstLine(python->python().lastError());
          const std::string raised = "the callable raised ";
          const auto at = e.find(raised);
          out.python_error =
              at == std::string::npos ? e.substr(e.find(": ") + 2) : e.substr(at + raised.size());
          out.report += " The Python function failed in " +
                        std::to_string(python->python().failures() - failures_before) +
                        " evaluations; the last: " + out.python_error;
        }
        return out;
      },
      py::arg("factor"), py::arg("trials") = 200, py::arg("step") = 1e-6,
      py::arg("tolerance") = 1e-6, py::arg("seed") = 1, py::arg("accept") = nullptr,
      "The factor's Jacobians against central differences at random states "
      "(core/jacobian_check.h).");
}

}  // namespace hamal::python
