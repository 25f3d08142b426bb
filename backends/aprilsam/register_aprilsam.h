// Registration of the AprilSAM back-end and the variants the thesis
// evaluates (sec. 3.5.1): aprilsam, aprilsam-fullsolve, aprilsam-periodic,
// aprilsam-nopredictive. One factory, other option defaults.
#pragma once

#include "core/registry.h"

namespace hamal {

void registerAprilSamBackends(Registry& registry);

}  // namespace hamal
