// Back-ends in Python (core/backend.h, core/registry.h, core/plugin.h):
// made by spec string from the module's Registry, fed Steps, returning the
// UpdateResult as an object. update() releases the GIL (a Python factor's
// cost function takes it back, so Ceres' threads may call it) and checks
// the step's Python factors first, so a broken callable is an exception and
// the back-end stays as it was, as checkStep guarantees for bad input.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <chrono>

#include "backend_handle.h"
#include "bindings.h"
#include "core/error.h"
#include "core/plugin.h"
#include "core/step.h"
#include "python_factor.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

// Each new Python factor, at the step's new values and the back-end's estimate.
void checkPythonFactors(const Step& step, const Values& known) {
  for (const FactorPtr& f : step.new_factors)
    if (const auto* p = dynamic_cast<const PythonFactor*>(f.get()))
      p->check(step.new_values, known);
}

}  // namespace

TimedUpdateResult BackendHandle::update(const Step& step) {
  checkPythonFactors(step, backend->estimate());
  const std::uint64_t failures_before = pythonFactorFailures();
  TimedUpdateResult out;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    static_cast<UpdateResult&>(out) = backend->update(step);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  if (!out.status.ok() && pythonFactorFailures() != failures_before)
    out.status.message += " (a Python factor failed: " + lastPythonFactorError() + ")";
  return out;
}

void bindBackends(py::module_& m) {
  py::class_<Status>(m, "Status", "ok, or a numerical failure naming the variables involved.")
      .def_property_readonly("code", [](const Status& s) { return std::string(toString(s.code)); })
      .def_readonly("message", &Status::message)
      .def_readonly("keys", &Status::keys)
      .def("ok", &Status::ok)
      .def("__bool__", &Status::ok)
      .def("__repr__", [](const Status& s) {
        return "<hamal.Status " + std::string(toString(s.code)) +
               (s.message.empty() ? "" : ": " + s.message) + ">";
      });

  py::class_<PhaseTimes>(m, "PhaseTimes", "Seconds per phase of one update (core/backend.h).")
      .def_readonly("linearize", &PhaseTimes::linearize)
      .def_readonly("order", &PhaseTimes::order)
      .def_readonly("factor", &PhaseTimes::factor)
      .def_readonly("solve", &PhaseTimes::solve)
      .def_readonly("other", &PhaseTimes::other)
      .def_readonly("estimate", &PhaseTimes::estimate)
      .def("total", &PhaseTimes::total)
      .def("__repr__", [](const PhaseTimes& t) {
        return "<hamal.PhaseTimes total " + std::to_string(t.total()) + " s>";
      });

  py::class_<TimedUpdateResult>(m, "UpdateResult", "What one update did (core/backend.h).")
      .def_property_readonly(
          "kind", [](const TimedUpdateResult& r) { return std::string(toString(r.kind)); })
      .def_readonly("reason", &UpdateResult::reason)
      .def_readonly("status", &UpdateResult::status)
      .def_readonly("iterations", &UpdateResult::iterations)
      .def_readonly("variables", &UpdateResult::variables)
      .def_readonly("variables_relinearized", &UpdateResult::variables_relinearized)
      .def_readonly("columns_recomputed", &UpdateResult::columns_recomputed)
      .def_readonly("columns_total", &UpdateResult::columns_total)
      .def_readonly("time", &UpdateResult::time)
      .def_readonly("seconds", &TimedUpdateResult::seconds,
                    "Wall time of the update call (steady clock).")
      .def("__repr__", [](const TimedUpdateResult& r) {
        return "<hamal.UpdateResult " + std::string(toString(r.kind)) +
               (r.reason.empty() ? "" : " (" + r.reason + ")") + ", " + toString(r.status.code) +
               ", " + std::to_string(r.seconds) + " s>";
      });

  py::class_<Step>(m, "Step",
                   "One update's input: new variables with guesses, new factors, fixed keys.")
      .def(py::init([](std::size_t index, const Values& new_values,
                       std::vector<FactorPtr> new_factors, std::vector<Key> fixed) {
             for (std::size_t i = 0; i < new_factors.size(); ++i)
               if (!new_factors[i])
                 throw Error("new_factors: entry " + std::to_string(i) + " is None");
             return Step{index, new_values, std::move(new_factors), std::move(fixed)};
           }),
           py::arg("index") = 0, py::arg("new_values") = Values(),
           py::arg("new_factors") = std::vector<FactorPtr>{}, py::arg("fixed") = std::vector<Key>{})
      .def_readwrite("index", &Step::index)
      .def_readwrite("new_values", &Step::new_values)
      .def_readwrite("new_factors", &Step::new_factors)
      .def_readwrite("fixed", &Step::fixed)
      .def("__repr__", [](const Step& s) {
        return "<hamal.Step " + std::to_string(s.index) + ": " +
               std::to_string(s.new_values.size()) + " new variables, " +
               std::to_string(s.new_factors.size()) + " factors>";
      });

  py::class_<BackendHandle>(m, "Backend", "A back-end made by hamal.backend(spec).")
      .def("update", &BackendHandle::update, py::arg("step"),
           "Adds the step and updates the estimate; hamal.Error on bad input (the back-end "
           "unchanged).")
      .def(
          "estimate", [](const BackendHandle& b) { return Values(b.backend->estimate()); },
          "A copy of the current estimate (O(variables): in a loop, read single variables with "
          "pose()).")
      .def(
          "pose", [](const BackendHandle& b, Key k) { return b.backend->estimate().pose(k); },
          py::arg("key"), "The current estimate of one pose, without copying the estimate.")
      .def(
          "point", [](const BackendHandle& b, Key k) { return b.backend->estimate().point(k); },
          py::arg("key"))
      .def("__contains__",
           [](const BackendHandle& b, Key k) { return b.backend->estimate().contains(k); })
      .def("__len__", [](const BackendHandle& b) { return b.backend->estimate().size(); })
      .def_readonly("spec", &BackendHandle::spec)
      .def_readonly("options", &BackendHandle::options,
                    "Every option with its value (defaults filled in).")
      .def("__repr__", [](const BackendHandle& b) { return "<hamal.Backend " + b.spec + ">"; });

  m.def(
      "backend",
      [](const std::string& spec) {
        const BackendSpec parsed = BackendSpec::parse(spec);
        BackendHandle h;
        h.options = registry().resolveOptions(parsed).values();
        h.backend = registry().makeBackend(parsed);
        h.spec = spec;
        return h;
      },
      py::arg("spec"), "A back-end from a spec 'name:key=value,...' (hamal.list_backends()).");

  m.def(
      "list_backends",
      []() {
        py::list out;
        for (const BackendInfo* b : registry().backends()) {
          py::list options;
          for (const OptionSpec& o : b->options)
            options.append(py::dict(py::arg("name") = o.name, py::arg("default") = o.default_value,
                                    py::arg("help") = o.help));
          out.append(py::dict(py::arg("name") = b->name, py::arg("description") = b->description,
                              py::arg("options") = options));
        }
        return out;
      },
      "Every back-end: name, description and options (name, default, help).");
  m.def(
      "list_factors",
      []() {
        py::list out;
        for (const FactorInfo* f : registry().factors())
          out.append(py::dict(py::arg("format") = f->format, py::arg("tag") = f->tag,
                              py::arg("description") = f->description));
        return out;
      },
      "Every factor kind the readers know: format, tag, description of the fields.");
  m.def("describe_backends", []() { return registry().describeBackends(); });
  m.def("describe_factors", []() { return registry().describeFactors(); });
  m.def(
      "load_plugin", [](const std::string& path) { loadPlugin(path, registry()); }, py::arg("path"),
      "Loads a plugin's shared library into the module's registry (core/plugin.h).");
  m.def(
      "load_plugins_from_path",
      [](const std::string& env_var) { return loadPluginsFromPath(registry(), env_var.c_str()); },
      py::arg("env_var") = "HAMAL_PLUGIN_PATH");
}

}  // namespace hamal::python
