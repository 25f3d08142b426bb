// BHAMD and AMD orderings for comparison with the min-heap ordering
// (thesis sec. 3.5.1, AprilSAM-NoPredictiveOrder); see the header.
#include "backends/aprilsam/bhamd_ordering.h"

#include <amd.h>

#include <string>

#include "backends/aprilsam/min_heap_ordering.h"
#include "core/error.h"

namespace hamal::aprilsam {

std::vector<int> bhamdOrdering(const OrderingInput& in) {
  std::vector<int> last;
  if (in.newest >= 0) last.push_back(in.newest);
  return scoreListOrdering(in, last, Rescoring::kOnExtraction);
}

std::vector<int> amdOrdering(const OrderingInput& in) {
  const std::vector<std::vector<int>> sym = symmetricAdjacency(in);
  const int n = static_cast<int>(sym.size());
  std::vector<int> column_start(n + 1, 0);
  std::vector<int> rows;
  for (int j = 0; j < n; ++j) {
    rows.insert(rows.end(), sym[j].begin(), sym[j].end());
    column_start[j + 1] = static_cast<int>(rows.size());
  }
  std::vector<int> order(n);
  if (n == 0) return order;
  if (rows.empty()) rows.push_back(0);  // amd_order rejects a null Ai even with no entries
  const int status = amd_order(n, column_start.data(), rows.data(), order.data(), nullptr, nullptr);
  if (status != AMD_OK && status != AMD_OK_BUT_JUMBLED) {
    throw Error("ordering: amd_order failed with status " + std::to_string(status) +
                (status == AMD_OUT_OF_MEMORY ? " (out of memory)" : ""));
  }
  return order;
}

}  // namespace hamal::aprilsam
