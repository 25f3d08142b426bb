// The built-in factor kinds and back-ends, registered in one call. The
// executables start from this and add plugins (core/plugin.h) on top.
#pragma once

#include "core/registry.h"

namespace hamal {

void registerBuiltins(Registry& registry);

// Registration functions of each folder, called by registerBuiltins.
void registerFactors(Registry& registry);           // factors/register_factors.cc
void registerCeresBackend(Registry& registry);      // backends/ceres/
void registerCholeskyBackend(Registry& registry);   // backends/cholesky/
void registerAprilSamBackends(Registry& registry);  // backends/aprilsam/register_aprilsam.cc

}  // namespace hamal
