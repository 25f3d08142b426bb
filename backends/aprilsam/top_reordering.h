// The re-elimination of the top of R in a new order (hamal's
// reeliminate=top, as iSAM2 re-eliminates the top of its Bayes tree; the
// affected rows of thesis sec. 3.4.2, figs. 3.5-3.6, taken with the rows of
// relinearised variables and given a fresh order instead of keeping theirs).
//
// The kept rows keep their numbers and their relative order and come
// first, then the top's positions in the new order. The top is factored by
// the left-looking factorisation from the factors' share on it, the kept
// rows' share R_NT^T R_NT (each untouched subtree's marginal on its
// separator, which iSAM2 caches per clique) subtracted as it goes, so the
// top's pattern is that of the graph and the separators, not the old
// order's fill.
#pragma once

#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/cholesky_factor.h"
#include "backends/aprilsam/left_looking_factorization.h"

namespace hamal::aprilsam {

// The rows a re-elimination must redo: those of the positions in `path`
// (eq. 3.14's S), of every row that references a position in `relin` (a
// variable moved to a new linearisation point changes the share of each of
// its factors, and each such factor is in the row of its first variable,
// which references the moved one), and all their elimination-tree
// ancestors. Ascending, closed under parent().
std::vector<int> topOfFactor(const CholeskyFactor& r, const std::vector<int>& path,
                             const std::vector<int>& relin);

// Re-eliminates the rows `top` (as topOfFactor returns them) of r in the
// order `order` (a permutation of top), from h, the factors' share on the
// top at the new positions (see IncrementalCholesky::reorderTop). new_pos[p]
// is the new position of old position p; aff becomes the top's new
// positions. On a failure (at old position failed_position) r is left
// renumbered without the top's rows: the caller must start again with a
// batch.
FactorUpdateOutcome reorderFactorTop(CholeskyFactor& r, AffectedRows& aff,
                                     LeftLookingFactorization& refactor,
                                     const std::vector<int>& top, const std::vector<int>& order,
                                     const BlockNormalEquations& h, std::vector<int>* new_pos);

}  // namespace hamal::aprilsam
