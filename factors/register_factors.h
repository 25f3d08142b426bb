// Registration of the built-in factor kinds by file format and tag (the
// table of lines is at the top of register_factors.cc). Called by
// registerBuiltins (backends/builtins.h); a program that wants only the
// factor kinds, without the back-ends, can call it on its own.
#pragma once

#include "core/registry.h"

namespace hamal {

void registerFactors(Registry& registry);

}  // namespace hamal
