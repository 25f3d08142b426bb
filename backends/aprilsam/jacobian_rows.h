// JacobianRows: the new factors of an incremental step as rows of the
// whitened Jacobian W and right side e = -r, so that A_new = W^T W and
// b_new = W^T e (thesis eq. 3.5-3.7 before they are multiplied out).
//
// IncrementalCholesky::addRows folds these rows into R directly, one
// Householder reflection per scalar column of each affected row, instead of
// forming R_aff^T R_aff + A_new and refactoring it (eq. 3.14): the same R~
// and y~, at a cost linear rather than quadratic in the width of the rows
// (householder_rank_update.h). Variables are addressed by their position in
// the elimination order and have any dimension up to kMaxDim.
#pragma once

#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "core/linearization.h"

namespace hamal::aprilsam {

class JacobianRows {
 public:
  // One factor's rows: `rows` residuals over the blocks at positions
  // `cols` (increasing), stored column-major as rows x (width + 1) numbers
  // at `offset` in values(), the last column being e = -r.
  struct Group {
    int rows = 0;
    int width = 0;  // scalar columns of the blocks (sum of their dimensions)
    int offset = 0;
    std::vector<int> cols;
    std::vector<int> dims;
  };

  void clear();
  // Adds the rows of one linearised factor whose k-th key sits at position
  // pos[k] with dimension dims[k].
  void add(const Linearization& lin, const int* pos, const int* dims);

  const std::vector<Group>& groups() const { return groups_; }
  int totalRows() const { return total_rows_; }
  const double* values() const { return values_.data(); }

 private:
  std::vector<Group> groups_;
  std::vector<double> values_;
  std::vector<int> order_;
  int total_rows_ = 0;
};

}  // namespace hamal::aprilsam
