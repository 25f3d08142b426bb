// Selection: the indicator vector alpha of thesis eq. 5.4 (alpha_j = 1 keeps
// map node j), shared by the three node-selection methods of sec. 5.4.
#pragma once

#include <string>
#include <vector>

#include "core/error.h"

namespace hamal::moss {

using Selection = std::vector<char>;

inline std::vector<int> selectedNodes(const Selection& a) {
  std::vector<int> out;
  for (std::size_t j = 0; j < a.size(); ++j)
    if (a[j]) out.push_back(static_cast<int>(j));
  return out;
}

// C must lie in [1, M].
inline void checkMapSize(int c, std::size_t m, const char* method) {
  if (c < 1 || static_cast<std::size_t>(c) > m)
    throw Error(std::string(method) + ": C = " + std::to_string(c) +
                " nodes requested from a map of M = " + std::to_string(m) +
                " nodes (C must be in [1, M])");
}

}  // namespace hamal::moss
