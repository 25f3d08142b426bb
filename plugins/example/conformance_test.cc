// The example plugin's back-end through hamal's conformance suite
// (conformance/backend_conformance.h, hamal::testing): the plugin is loaded
// as any user loads it, and its back-end keeps every contract a built-in one
// keeps, and ends the thesis protocol at cholesky's optimum.
#include "conformance/backend_conformance.h"

// The plugin this test loads: set by CMakeLists.txt to the one just built.
#ifndef HAMAL_EXAMPLE_PLUGIN
#error "HAMAL_EXAMPLE_PLUGIN must name the plugin's shared library"
#endif

HAMAL_BACKEND_CONFORMANCE(ExamplePlugin,
                          hamal::testing::registered("dense-gauss-newton:tolerance=1e-12",
                                                     {HAMAL_EXAMPLE_PLUGIN}));
