// The hamal Python module's entry point (python/README.md): the one
// Registry (the built-in back-ends with the robust options), the exception
// mapping (hamal::Error -> hamal.Error, a ValueError with the same
// message), and the bind functions of the other files. The Python package
// hamal/ re-exports this and adds the factor kinds by name and a run loop
// in Python.
#include <pybind11/pybind11.h>

#include "apps/robust/robust_loop_closures.h"
#include "backends/builtins.h"
#include "bindings.h"
#include "core/error.h"
#include "core/plugin.h"

namespace py = pybind11;

namespace hamal::python {

Registry& registry() {
  static Registry* r = [] {
    Registry builtins;
    registerBuiltins(builtins);
    // The back-ends take the robust options as hamal_solve's do (GNC and PCM
    // wrap the back-end; backend_bindings.cc refuses the models that change
    // the factors). Never destroyed: plugins' factories live as long as the
    // process.
    return new Registry(apps::robustRegistry(builtins));
  }();
  return *r;
}

void warnDeprecated(const char* message) {
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message, 1) < 0) throw py::error_already_set();
}

}  // namespace hamal::python

PYBIND11_MODULE(_hamal, m) {
  m.doc() = "hamal: factor-graph back-ends for 2D SLAM (the compiled part; import hamal)";
  py::register_exception<hamal::Error>(m, "Error", PyExc_ValueError).attr("__doc__") =
      "Bad input (a file line, an argument, a key, a step): a ValueError whose message names "
      "where and why ('file:line: reason', 'argument: reason').";
  hamal::python::bindGeometry(m);
  hamal::python::bindFactors(m);
  hamal::python::bindPythonFactor(m);
  hamal::python::bindBackends(m);
  hamal::python::bindProtocol(m);
}
