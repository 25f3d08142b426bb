// IncrementalCholesky: see incremental_cholesky.h (thesis sec. 3.4.1-3.4.2,
// eq. 3.14 and 3.19).
#include "backends/aprilsam/incremental_cholesky.h"

#include <numeric>

#include "backends/aprilsam/top_reordering.h"

namespace hamal::aprilsam {

void IncrementalCholesky::reset(const std::vector<int>& dims) {
  const int n = static_cast<int>(dims.size());
  r_.reset(dims);
  aff_.positions.clear();
  aff_.index.assign(n, -1);
  refactor_.resize(n);
  rank_.resize(n);
}

void IncrementalCholesky::append(int dim) {
  r_.append(dim);
  aff_.index.push_back(-1);
  refactor_.append();
  rank_.append();
}

IncrementalCholesky::Outcome IncrementalCholesky::update(const BlockNormalEquations& a_new,
                                                         bool all) {
  // A batch after reset() reads no old row, so it writes R's rows in place
  // instead of into work rows that commit() would copy.
  const bool in_place = all && r_.empty();
  // aff = S and its elimination-tree ancestors (figs. 3.5, 3.6).
  aff_.positions.clear();
  if (all) {
    aff_.positions.resize(size());
    std::iota(aff_.positions.begin(), aff_.positions.end(), 0);
  } else {
    for (int s : a_new.touched()) aff_.addPathToRoot(r_, s);
  }
  aff_.indexPositions();
  return refactor_.factor(r_, aff_, a_new, in_place);
}

IncrementalCholesky::Outcome IncrementalCholesky::reorderTop(const std::vector<int>& top,
                                                             const std::vector<int>& order,
                                                             const BlockNormalEquations& h,
                                                             std::vector<int>* new_pos) {
  return reorderFactorTop(r_, aff_, refactor_, top, order, h, new_pos);
}

}  // namespace hamal::aprilsam
