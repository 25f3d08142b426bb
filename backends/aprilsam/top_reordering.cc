// The re-elimination of the top of R: see top_reordering.h.
#include "backends/aprilsam/top_reordering.h"

namespace hamal::aprilsam {

std::vector<int> topOfFactor(const CholeskyFactor& r, const std::vector<int>& path,
                             const std::vector<int>& relin) {
  const int n = r.size();
  std::vector<char> in(n, 0);
  for (int s : path) in[s] = 1;
  for (int q : relin) {
    in[q] = 1;
    r.forEachRowReferencing(q, [&](int row) { in[row] = 1; });
  }
  // Ancestors have larger positions: one ascending pass closes the set.
  std::vector<int> top;
  for (int p = 0; p < n; ++p) {
    if (!in[p]) continue;
    top.push_back(p);
    if (r.parent(p) >= 0) in[r.parent(p)] = 1;
  }
  return top;
}

FactorUpdateOutcome reorderFactorTop(CholeskyFactor& r, AffectedRows& aff,
                                     LeftLookingFactorization& refactor,
                                     const std::vector<int>& top, const std::vector<int>& order,
                                     const BlockNormalEquations& h, std::vector<int>* new_pos) {
  const int n = r.size();
  const int nt = static_cast<int>(top.size());
  const int nn = n - nt;
  std::vector<int> local(n, -1);  // old position -> index in the top's new order
  for (int k = 0; k < nt; ++k) local[order[k]] = k;
  std::vector<int>& np = *new_pos;
  np.assign(n, -1);
  std::vector<int> kept;
  kept.reserve(nn);
  for (int p = 0; p < n; ++p) {
    if (local[p] >= 0) {
      np[p] = nn + local[p];
    } else {
      np[p] = static_cast<int>(kept.size());
      kept.push_back(p);
    }
  }
  r.moveTopLast(kept, order, np);
  FactorUpdateOutcome out = refactor.factorTop(r, aff, h, nn);
  if (!out.ok) out.failed_position = order[out.failed_position - nn];
  return out;
}

}  // namespace hamal::aprilsam
