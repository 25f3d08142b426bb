// Equidistant: C map nodes spaced uniformly along the mapping trajectory
// (thesis sec. 5.4.1, eq. 5.6): node i (1-based) is kept when
// i = floor(k M / (C + 1)) for k = 1..C, so C = 1 keeps the middle node.
#pragma once

#include "apps/moss/selection.h"

namespace hamal::moss {

Selection equidistant(std::size_t m, int c);

}  // namespace hamal::moss
