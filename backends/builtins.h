// The built-in factor kinds and back-ends, registered in one call. The
// executables start from this and add plugins (core/plugin.h) on top.
//
// It lives with the back-ends, not in core/, because it names every concrete
// factor kind and back-end: core/ holds only the contracts they implement.
#pragma once

#include "core/registry.h"

namespace hamal {

// factors/register_factors.h, then ceres, cholesky and the AprilSAM family.
void registerBuiltins(Registry& registry);

}  // namespace hamal
