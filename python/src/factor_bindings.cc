// Factors and graphs in Python (core/factor.h, core/graph.h,
// core/graph_io.h). Factors are made through the Registry, the way the
// readers make them: a line of the kind's file form is parsed by the kind
// registered for (format, tag), so every kind, a plugin's included, is
// available without a binding per class and with the reader's checks and
// messages (hamal/factors.py builds the lines from numpy arguments).
#include <ceres/loss_function.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "backend_handle.h"
#include "bindings.h"
#include "core/error.h"
#include "core/graph.h"
#include "core/graph_io.h"
#include "core/line_tokens.h"
#include "core/linearization.h"
#include "core/relative_pose_measurement.h"
#include "factors/between_factor.h"
#include "python_factor.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

std::vector<const double*> parameters(const Factor& f, const Values& values) {
  std::vector<const double*> p;
  const auto& sizes = f.costFunction()->parameter_block_sizes();
  for (std::size_t k = 0; k < f.keys().size(); ++k) {
    const Key key = f.keys()[k];
    if (values.dim(key) != sizes[k])  // dim() throws for a missing key
      throw Error("factor " + f.tag() + ": variable " + key.str() + " has dimension " +
                  std::to_string(values.dim(key)) + ", the factor expects " +
                  std::to_string(sizes[k]));
    p.push_back(values.data(key));
  }
  return p;
}

std::string line(const Factor& f) {
  std::ostringstream os;
  os << f.tag() << " ";
  f.writeFields(os);
  return os.str();
}

// A factor written in Python has no file form: refuse before writing.
void checkWritable(const std::vector<FactorPtr>& factors) {
  for (std::size_t i = 0; i < factors.size(); ++i) {
    if (!factors[i]) throw Error("factors: entry " + std::to_string(i) + " is None");
    if (const auto* p = dynamic_cast<const PythonFactor*>(factors[i].get()))
      throw Error("factors: entry " + std::to_string(i) + " (" + p->name() +
                  ") is written in Python and cannot be written to a file");
  }
}

BetweenResidual parseResidual(const std::string& name) {
  if (name == "thesis") return BetweenResidual::kThesis;
  if (name == "measurement" || name == "measurement-frame")
    return BetweenResidual::kMeasurementFrame;
  throw Error("residual: unknown between residual '" + name + "'; expected thesis or measurement");
}

}  // namespace

// Factor, and hamal.parse_factor that makes one by the registry.
static void bindFactor(py::module_& m) {
  py::class_<Factor, FactorPtr>(m, "Factor",
                                "One measurement: keys and a whitened residual (core/factor.h).")
      .def_property_readonly("keys", &Factor::keys,
                             "The variables the factor connects, in the order of its Jacobians.")
      .def_property_readonly(
          "dims", [](const Factor& f) { return f.costFunction()->parameter_block_sizes(); },
          "The dimension of each key's variable, in the order of keys (3 a pose, 2 a point).")
      .def_property_readonly("residual_dim", &Factor::residualDim,
                             "The length of the whitened residual.")
      .def_property_readonly("tag", &Factor::tag,
                             "The kind's tag in g2o files ('EDGE_SE2', ...; 'PYTHON_FACTOR').")
      .def_property_readonly(
          "has_loss", [](const Factor& f) { return f.lossFunction() != nullptr; },
          "True when the factor has a robust loss (set_loss).")
      .def(
          "set_loss",
          [](Factor& f, py::object kind, double scale) {
            if (heldByBackend(f))
              throw Error("set_loss: the factor " + f.tag() +
                          " is in a back-end, which evaluates it with its loss (from another "
                          "thread, too); set the loss before Backend.update, or on a copy "
                          "(hamal.parse_factor(f.line()))");
            if (kind.is_none()) return f.setLoss(nullptr);
            const std::string k = kind.cast<std::string>();
            if (!(scale > 0) || !std::isfinite(scale))
              throw Error("scale: must be positive and finite, got " + std::to_string(scale));
            if (k == "huber") return f.setLoss(std::make_shared<ceres::HuberLoss>(scale));
            if (k == "cauchy") return f.setLoss(std::make_shared<ceres::CauchyLoss>(scale));
            if (k == "soft_l1") return f.setLoss(std::make_shared<ceres::SoftLOneLoss>(scale));
            if (k == "arctan") return f.setLoss(std::make_shared<ceres::ArctanLoss>(scale));
            if (k == "tukey") return f.setLoss(std::make_shared<ceres::TukeyLoss>(scale));
            throw Error("kind: unknown loss '" + k +
                        "'; expected huber, cauchy, soft_l1, arctan, tukey or None");
          },
          py::arg("kind"), py::arg("scale") = 1.0,
          "Gives the factor Ceres' robust loss `kind` with scale a on the whitened residual (None: "
          "none).\n"
          "It changes the factor wherever it is held; hamal.Error once the factor is in a "
          "back-end.\n"
          "chi2 stays without the loss (docs/PROTOCOL.md); the back-ends minimise with it.")
      .def("line", &line, "The factor's line in g2o's file form (tag and fields).")
      .def(
          "residual",
          [](const Factor& f, const Values& v) {
            const auto p = parameters(f, v);
            Eigen::VectorXd r(f.residualDim());
            if (!f.costFunction()->Evaluate(p.data(), r.data(), nullptr))
              throw Error("factor " + f.tag() +
                          ": the residual cannot be evaluated at these values");
            return r;
          },
          py::arg("values"), "The whitened residual at `values` (no robust loss).")
      .def(
          "chi2",
          [](const Factor& f, const Values& v) {
            parameters(f, v);
            return f.chi2(v);
          },
          py::arg("values"), "|whitened residual|^2: this factor's term of chi2.")
      .def(
          "linearize",
          [](const Factor& f, const Values& v) {
            const auto p = parameters(f, v);
            Linearization lin;
            if (!linearize(f, p.data(), &lin))
              throw Error("factor " + f.tag() + ": cannot be linearized at these values");
            std::vector<Eigen::MatrixXd> js(lin.jacobians.begin(), lin.jacobians.end());
            return py::make_tuple(lin.residual, js);
          },
          py::arg("values"),
          "(residual, [J_k]) at `values`, robust loss applied as the back-ends apply it.")
      .def(
          "relative_pose",
          [](const Factor& f) -> py::object {
            const auto rp = relativePoseOf(f);
            if (!rp) return py::none();
            return py::make_tuple(rp->from, rp->to, rp->measurement,
                                  Eigen::Matrix3d(rp->information));
          },
          "(from, to, measurement, information) for a relative-pose measurement, else None.")
      .def("__repr__", [](const Factor& f) {
        std::string keys;
        for (Key k : f.keys()) keys += (keys.empty() ? "" : ", ") + k.str();
        return "<hamal.Factor " + f.tag() + " on " + keys + ">";
      });

  m.def(
      "parse_factor",
      [](const std::string& text, const std::string& format, const std::string& name) {
        parseFormat(format);
        LineTokens tokens = LineTokens::split(name, 1, text);
        if (tokens.size() == 0) throw Error(name + ":1: empty factor line");
        tokens.setRegistry(&registry(), format);
        return registry().parseFactor(std::move(tokens));
      },
      py::arg("line"), py::arg("format") = "g2o", py::arg("name") = "<line>",
      "A factor from one line of a file (tag first), by the kind the registry holds for (format, "
      "tag).");
}

// Graph: factors, initial values, fixed keys.
static void bindGraph(py::module_& m) {
  py::class_<Graph>(m, "Graph",
                    "A factor graph: factors, initial values, fixed variables. len(g) is the "
                    "number of factors, g[i] the i-th.")
      .def(py::init<>(), "An empty graph.")
      .def_readwrite("source", &Graph::source, "The file it was read from ('' if built in code).")
      .def_readwrite("initial", &Graph::initial,
                     "The initial values the file gave (a copy on reading; assign to replace).")
      .def_readwrite("factors", &Graph::factors,
                     "The factors in file order (a new list on reading; assign to replace).")
      .def_readwrite("fixed", &Graph::fixed,
                     "The keys held fixed (FIX lines; a new set on reading).")
      .def(
          "add",
          [](Graph& g, FactorPtr f) {
            if (!f) throw Error("factor: None");
            g.add(std::move(f));
          },
          py::arg("factor"), "Appends a factor.")
      .def(
          "fix", [](Graph& g, Key k) { g.fixed.insert(k); }, py::arg("key"),
          "Holds a variable fixed (as a g2o FIX line).")
      .def("keys", &Graph::keys,
           "Every key of the factors and initial values, sorted (computed: a new list).")
      .def("__len__", [](const Graph& g) { return g.factors.size(); })
      .def("__getitem__",
           [](const Graph& g, long i) {
             if (i < 0) i += long(g.factors.size());
             if (i < 0 || i >= long(g.factors.size()))
               throw py::index_error("factor index out of range");
             return g.factors[std::size_t(i)];
           })
      .def(
          "write",
          [](const Graph& g, const std::string& path, py::object values,
             const std::string& format) {
            checkWritable(g.factors);
            writeGraph(path, values.is_none() ? g.initial : values.cast<const Values&>(), g.factors,
                       parseFormat(format), g.fixed);
          },
          py::arg("path"), py::arg("values") = py::none(), py::arg("format") = "g2o",
          "Writes `values` (the graph's initial values by default) and the factors as g2o (with "
          "FIX lines), or as a TORO or GTSAM pose graph (format 'toro', 'gtsam': poses and "
          "between factors only, else hamal.Error naming what the format cannot hold).")
      .def("__repr__", [](const Graph& g) {
        return "<hamal.Graph " + (g.source.empty() ? std::string("(built in code)") : g.source) +
               ": " + std::to_string(g.factors.size()) + " factors, " +
               std::to_string(g.initial.size()) + " initial values>";
      });
}

// Graphs from and to files and text, and the between residual's switch.
static void bindGraphFiles(py::module_& m) {
  m.def(
      "read_graph",
      [](const std::string& path, const std::string& format) {
        return readGraph(path, registry(), parseFormat(format));
      },
      py::arg("path"), py::arg("format") = "auto",
      "Reads a g2o, TORO or GTSAM file (format auto, g2o, toro, gtsam); hamal.Error('file:line: "
      "reason') on bad input.");
  m.def(
      "parse_graph",
      [](const std::string& text, const std::string& name, const std::string& format) {
        std::istringstream in(text);
        return readGraph(in, name, registry(), parseFormat(format));
      },
      py::arg("text"), py::arg("name") = "<string>", py::arg("format") = "g2o",
      "Reads a graph from the text of a file; `name` is the file name in messages.");
  m.def(
      "write_g2o",
      [](const std::string& path, const Values& values, const std::vector<FactorPtr>& factors,
         const std::set<Key>& fixed) {
        checkWritable(factors);
        writeG2o(path, values, factors, fixed);
      },
      py::arg("path"), py::arg("values"), py::arg("factors"), py::arg("fixed") = std::set<Key>{},
      "Writes values, factors and FIX lines as a g2o file; hamal.Error for a Python factor.");
  m.def(
      "g2o_text",
      [](const Values& values, const std::vector<FactorPtr>& factors, const std::set<Key>& fixed) {
        checkWritable(factors);
        std::ostringstream os;
        writeG2o(os, values, factors, fixed);
        return os.str();
      },
      py::arg("values"), py::arg("factors"), py::arg("fixed") = std::set<Key>{},
      "What write_g2o would write, as a string.");
  m.def(
      "set_between_residual",
      [](Graph& g, const std::string& residual) {
        return setBetweenResidual(g, parseResidual(residual));
      },
      py::arg("graph"), py::arg("residual"),
      "Switches every between factor to the 'thesis' or 'measurement' (g2o's, GTSAM's) residual.");
}

// In this order: a class is registered before a signature names it.
void bindFactors(py::module_& m) {
  bindFactor(m);
  bindGraph(m);
  bindGraphFiles(m);
}

}  // namespace hamal::python
