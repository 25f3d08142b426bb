// Registration of the "ceres" back-end (ceres_backend.h), apart from the
// back-end's own header so that a caller that only registers it does not
// need that header's dependencies.
#pragma once

#include "core/registry.h"

namespace hamal {

void registerCeresBackend(Registry& registry);

}  // namespace hamal
