// Equidistant: see equidistant.h (thesis eq. 5.6).
#include "apps/moss/equidistant.h"

#include <algorithm>

namespace hamal::moss {

Selection equidistant(std::size_t m, int c) {
  checkMapSize(c, m, "Equidistant");
  Selection a(m, 0);
  if (static_cast<std::size_t>(c) == m) return Selection(m, 1);
  for (int k = 1; k <= c; ++k) {
    // 1-based i = floor(k M / (C + 1)) >= 1 since C < M; distinct since the
    // spacing M / (C + 1) > 1 whenever C < M.
    const std::size_t i = static_cast<std::size_t>(k) * m / static_cast<std::size_t>(c + 1);
    a[std::clamp<std::size_t>(i, 1, m) - 1] = 1;
  }
  return a;
}

}  // namespace hamal::moss
