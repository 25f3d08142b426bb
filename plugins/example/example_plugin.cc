// The example plugin's entry point (core/plugin.h).
//
// The pattern: a shared library built against hamal's public headers and
// linked to libhamal, whose one exported entry point (HAMAL_PLUGIN) adds
// factor kinds and back-ends to the registry it is given. The executables
// load it with --plugin path or from HAMAL_PLUGIN_PATH; the loader hands it
// an empty staging registry and merges it all or nothing, so registering
// here needs no care about what is already there. Nothing in this folder is
// known to hamal at build time.
//
// This plugin adds
//   - the factor kind ("g2o", "EDGE_SE2_CAUCHY"): a between with a Cauchy
//     loss, readable from g2o files and written back (cauchy_between_factor.h);
//   - the back-end "dense-gauss-newton" (dense_gauss_newton.h).
#include "cauchy_between_factor.h"
#include "core/plugin.h"
#include "dense_gauss_newton.h"

HAMAL_PLUGIN(registry) {
  registry->addFactor(hamal::example::cauchyBetweenFactorInfo());
  registry->addBackend(hamal::example::denseGaussNewtonInfo());
}
