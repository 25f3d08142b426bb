// The pieces of the hamal Python module (python/README.md), one bind
// function per group of types, and the module's one Registry: built-ins,
// HAMAL_PLUGIN_PATH's plugins and those load_plugin adds, shared by every
// reader, factor and back-end made from Python, as the executables share
// theirs.
#pragma once

#include <pybind11/pybind11.h>

#include "core/registry.h"

namespace hamal::python {

Registry& registry();

// A DeprecationWarning for a renamed member (python/README.md, "Properties and
// methods"): the old spelling works and says what replaces it.
void warnDeprecated(const char* message);

void bindGeometry(pybind11::module_& m);      // Key, Pose2, Point2, Values and numpy
void bindFactors(pybind11::module_& m);       // Factor, the registry's kinds, Graph and files
void bindPythonFactor(pybind11::module_& m);  // factors written in Python, check_jacobians
void bindBackends(pybind11::module_& m);      // Backend, Step, UpdateResult, listings, plugins
void bindProtocol(pybind11::module_& m);      // step sources, metrics, LAGO

}  // namespace hamal::python
