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
           py::arg("predict") = py::none())
      .def_property_readonly("name", &PythonFactor::name)
      .def_property_readonly(
          "failures", [](const PythonFactor& f) { return f.python().failures(); },
          "How many evaluations failed (the callable raised or returned wrong shapes).")
      .def_property_readonly("last_error",
                             [](const PythonFactor& f) { return f.python().lastError(); })
      .def(
          "check", [](const PythonFactor& f, const Values& v) { f.check(v); }, py::arg("values"),
          "Evaluates once at `values`; hamal.Error naming the reason when the callable fails.")
      .def("__repr__", [](const PythonFactor& f) {
        std::string keys;
        for (Key k : f.keys()) keys += (keys.empty() ? "" : ", ") + k.str();
        return "<hamal.PythonFactor " + f.name() + " on " + keys + ">";
      });

  py::class_<JacobianCheckResult>(m, "JacobianCheckResult")
      .def_readonly("ok", &JacobianCheckResult::ok)
      .def_readonly("trials", &JacobianCheckResult::trials)
      .def_readonly("rejected", &JacobianCheckResult::rejected)
      .def_readonly("max_abs_error", &JacobianCheckResult::max_abs_error)
      .def_readonly("max_rel_error", &JacobianCheckResult::max_rel_error)
      .def_readonly("worst_block", &JacobianCheckResult::worst_block)
      .def_readonly("worst_row", &JacobianCheckResult::worst_row)
      .def_readonly("worst_col", &JacobianCheckResult::worst_col)
      .def_readonly("worst_analytic", &JacobianCheckResult::worst_analytic)
      .def_readonly("worst_numeric", &JacobianCheckResult::worst_numeric)
      .def_readonly("worst_state", &JacobianCheckResult::worst_state)
      .def_readonly("report", &JacobianCheckResult::report)
      .def("__bool__", [](const JacobianCheckResult& r) { return r.ok; })
      .def("__repr__", [](const JacobianCheckResult& r) {
        return "<hamal.JacobianCheckResult " + r.report + ">";
      });

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
        return checkJacobians(factor, o);
      },
      py::arg("factor"), py::arg("trials") = 200, py::arg("step") = 1e-6,
      py::arg("tolerance") = 1e-6, py::arg("seed") = 1, py::arg("accept") = nullptr,
      "The factor's Jacobians against central differences at random states "
      "(core/jacobian_check.h).");
}

}  // namespace hamal::python
