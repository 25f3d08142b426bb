// Built-in registrations: see builtins.h.
#include "backends/builtins.h"

#include "backends/aprilsam/register_aprilsam.h"
#include "backends/ceres/register_ceres.h"
#include "backends/cholesky/register_cholesky.h"
#include "factors/register_factors.h"

namespace hamal {

void registerBuiltins(Registry& registry) {
  registerFactors(registry);
  registerCeresBackend(registry);
  registerCholeskyBackend(registry);
  registerAprilSamBackends(registry);
}

}  // namespace hamal
