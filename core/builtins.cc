// Built-in registrations: see builtins.h.
#include "core/builtins.h"

namespace hamal {

void registerBuiltins(Registry& registry) {
  registerFactors(registry);
  registerCeresBackend(registry);
  registerCholeskyBackend(registry);
  registerAprilSamBackends(registry);
}

}  // namespace hamal
