// Step sources, metrics and LAGO in Python (core/step_source.h,
// protocol/thesis_protocol.h, core/metrics.h,
// protocol/lago_initialization.h). source.steps(backend) iterates the
// steps, each made in C++ from the back-end's current estimate without
// copying it into Python, so a Python loop costs what the bench's C++ loop
// costs plus one call per step (python/README.md, "Cost"); it holds the
// back-end's lock while it reads the estimate (backend_handle.h).
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "backend_handle.h"
#include "bindings.h"
#include "core/error.h"
#include "core/metrics.h"
#include "numpy_arguments.h"
#include "protocol/lago_initialization.h"
#include "protocol/thesis_protocol.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

struct StepIterator {
  StepSource* source;
  BackendHandle* backend;
  std::size_t next = 0;
  std::size_t end = 0;
};

}  // namespace

// StepIterator, StepSource and ThesisProtocol.
static void bindStepSources(py::module_& m) {
  py::class_<StepIterator>(m, "StepIterator",
                           "What StepSource.steps(backend) returns: each next() makes the next "
                           "step from the back-end's estimate; len() is the steps left.")
      .def("__iter__", [](StepIterator& it) -> StepIterator& { return it; })
      .def("__len__", [](const StepIterator& it) { return it.end - it.next; })
      .def("__next__", [](StepIterator& it) {
        if (it.next >= it.end) throw py::stop_iteration();
        // A PythonFactor's predict may run while the estimate is read.
        BackendHandle::Access access(*it.backend, "steps", true);
        return it.source->step(it.next++, it.backend->backend->estimate());
      });

  py::class_<StepSource>(m, "StepSource", "Where steps come from (core/step_source.h).")
      .def("__len__", &StepSource::size)
      .def(
          "size",
          [](const StepSource& s) {
            warnDeprecated("StepSource.size() is deprecated: use len(source)");
            return s.size();
          },
          "Deprecated: len(source), the number of steps.")
      .def(
          "step",
          [](StepSource& s, std::size_t i, const Values& estimate) {
            if (i >= s.size())
              throw Error("step: index " + std::to_string(i) + " >= " + std::to_string(s.size()) +
                          " steps");
            return s.step(i, estimate);
          },
          py::arg("index"), py::arg("estimate"), "Step i, its guesses made from `estimate`.")
      .def(
          "steps",
          [](StepSource& s, BackendHandle& b, std::size_t max_steps) {
            const std::size_t end = max_steps == 0 ? s.size() : std::min(max_steps, s.size());
            return StepIterator{&s, &b, 0, end};
          },
          py::arg("backend"), py::arg("max_steps") = 0, py::keep_alive<0, 1>(),
          py::keep_alive<0, 2>(),
          "Iterates the steps, each made from `backend`'s estimate at the time it is asked for;\n"
          "call backend.update(step) once per step.");

  py::class_<ThesisProtocol, StepSource>(m, "ThesisProtocol",
                                         "The thesis protocol over a graph (docs/PROTOCOL.md).")
      .def(py::init([](const Graph& g, bool add_prior, py::handle prior_information) {
             ThesisProtocol::Options o;
             o.add_prior = add_prior;
             const auto a = numericArray(prior_information, "prior_information", 3, 0);
             for (int i = 0; i < 3; ++i) {
               if (a.at(i) <= 0) throw Error("prior_information: entries must be positive");
               o.prior_information[i] = a.at(i);
             }
             return std::make_unique<ThesisProtocol>(g, o);
           }),
           py::arg("graph"), py::arg("add_prior") = true,
           py::arg("prior_information") = std::vector<double>{1e4, 1e4, 1e3},
           py::keep_alive<1, 2>(),
           "ThesisProtocol(graph, add_prior=True, prior_information=[1e4, 1e4, 1e3]): one step "
           "per pose; the gauge prior on the first pose has that diagonal information (1/m^2, "
           "1/m^2, 1/rad^2).")
      .def("initial_values", &ThesisProtocol::initialValues,
           "Odometry-composed guesses for every variable.")
      .def("batch", &ThesisProtocol::batch,
           "Everything in one step, from initial_values(): a batch solve.")
      .def_property_readonly(
          "prior", [](const ThesisProtocol& p) { return p.prior(); },
          "The gauge prior the protocol adds (not a dataset factor), or None.")
      .def(
          "pose",
          [](const ThesisProtocol& p, std::size_t i) {
            if (i >= p.size())
              throw Error("pose: index " + std::to_string(i) + " >= " + std::to_string(p.size()) +
                          " steps");
            return p.pose(i);
          },
          py::arg("index"), "The pose key of step i.");
}

// chi2 and the absolute trajectory error.
static void bindMetrics(py::module_& m) {
  m.def(
      "chi2",
      [](const std::vector<FactorPtr>& factors, const Values& values) {
        return chi2(factors, values);
      },
      py::arg("factors"), py::arg("values"),
      "Sum of |whitened residual|^2 without robust losses (docs/PROTOCOL.md, 'chi2').");

  py::class_<TrajectoryError>(m, "TrajectoryError",
                              "What absolute_trajectory_error returns (core/metrics.h).")
      .def_readonly("translation_rmse", &TrajectoryError::translation_rmse,
                    "RMSE of the positions over the common poses (m).")
      .def_readonly("rotation_rmse", &TrajectoryError::rotation_rmse,
                    "RMSE of the wrapped heading differences (rad).")
      .def_readonly("poses", &TrajectoryError::poses, "How many poses the RMSE is over.")
      .def("__repr__", [](const TrajectoryError& e) {
        return "<hamal.TrajectoryError " + std::to_string(e.poses) + " poses: translation " +
               std::to_string(e.translation_rmse) + " m, rotation " +
               std::to_string(e.rotation_rmse) + " rad>";
      });
  m.def(
      "absolute_trajectory_error",
      [](const Values& estimate, const Values& truth, bool align) {
        const TrajectoryError e = absoluteTrajectoryError(estimate, truth, align);
        if (e.poses == 0)  // an RMSE over nothing is no figure, least of all 0 m
          throw Error("absolute_trajectory_error: the estimate (" +
                      std::to_string(estimate.size()) + " variables) and the truth (" +
                      std::to_string(truth.size()) + " variables) have no pose in common");
        return e;
      },
      py::arg("estimate"), py::arg("truth"), py::arg("align") = true,
      "RMSE over the common poses, after the best rigid alignment by default; hamal.Error when "
      "there are none.");
}

// LAGO's initial values and what it used.
static void bindLago(py::module_& m) {
  py::class_<LagoResult>(m, "LagoResult",
                         "What hamal.lago returns: the initial values and what LAGO used.")
      .def_readonly("values", &LagoResult::values,
                    "`initial` with every pose connected to the anchor replaced by LAGO's.")
      .def_readonly("poses", &LagoResult::poses, "Poses solved (connected to the anchor).")
      .def_readonly("edges", &LagoResult::edges, "Relative-pose measurements used.")
      .def_readonly("followed", &LagoResult::followed,
                    "Other variables (landmarks) predicted again from the solved poses.")
      .def_property_readonly(
          "unused",
          [](const LagoResult& r) {
            py::list out;
            for (const auto& u : r.unused) out.append(py::make_tuple(u.factor, u.reason));
            return out;
          },
          "(factor, reason) for each factor between poses LAGO did not use.")
      .def(
          "describe", [](const LagoResult& r) { return describe(r); },
          "One line: what was used, and the unused factors counted by tag and reason.")
      .def("__repr__",
           [](const LagoResult& r) { return "<hamal.LagoResult " + describe(r) + ">"; });
  m.def(
      "lago",
      [](const std::vector<FactorPtr>& factors, const Values& initial_argument) {
        const Values initial = initial_argument;  // another thread may change it without the GIL
        py::gil_scoped_release release;
        return lagoInitialization(factors, initial);
      },
      py::arg("factors"), py::arg("initial"),
      "LAGO's initial values for the pose graph (protocol/lago_initialization.h).");
  m.def(
      "lago",
      [](const Graph& graph, const Values& initial_argument) {
        const Graph g = graph;  // copies of what another thread may change without the GIL
        const Values initial = initial_argument;
        py::gil_scoped_release release;
        return lagoInitialization(g, initial);
      },
      py::arg("graph"), py::arg("initial"),
      "LAGO's initial values for the graph's factors (the graph and values are copied first).");
}

// In this order: a class is registered before a signature names it.
void bindProtocol(py::module_& m) {
  bindStepSources(m);
  bindMetrics(m);
  bindLago(m);
}

}  // namespace hamal::python
