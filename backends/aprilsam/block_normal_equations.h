// BlockNormalEquations: the normal equations A = J^T J, b = -J^T r of a set of
// factors, assembled in blocks of each variable's dimension (3x3 for Pose2,
// 2x2 for Point2, 3x2 between them) from the factors' own Jacobians (thesis
// eq. 3.5-3.7, with A* and b* written A and b as in sec. 3.4).
//
// Variables are addressed by their position in the elimination order, so the
// blocks land where the factor R needs them: an incremental step fills it with
// the new factors only (A_new, b_new of eq. 3.14 and 3.19), a batch update with
// every factor. Only the upper triangle (row position <= column position) is
// kept; duplicate blocks are not merged here, the factorisation sums them.
#pragma once

#include <tuple>
#include <vector>

#include "backends/aprilsam/pooled_array.h"
#include "core/linearization.h"
#include "core/values.h"

namespace hamal::aprilsam {

// The largest variable dimension: a Values entry holds at most this many
// parameters, so per-variable vectors (b, y, dx) fit in arrays of this size.
constexpr int kMaxDim = static_cast<int>(std::tuple_size<decltype(Values::Entry::data)>::value);

class BlockNormalEquations {
 public:
  struct Block {
    int col;     // position of the column variable (>= the row's position)
    int offset;  // into values(): d_row x d_col numbers, column-major
  };

  // Empties the system (cost proportional to what was in it, not to the
  // number of positions) and makes room for positions 0..num_positions-1.
  void clear(int num_positions);

  // Adds sign x (J^T J and -J^T r) of one linearised factor whose k-th key
  // sits at position `pos[k]` with dimension `dims[k]`. sign = -1 takes a
  // factor's old linearisation out again when it is relinearised.
  void add(const Linearization& lin, const int* pos, const int* dims, double sign = 1.0);

  // Levenberg-style damping, used when the undamped system is not positive
  // definite: A_ii += lambda * max(diag(A_ii), floor) for every row.
  void damp(double lambda, double floor);

  // Positions that hold at least one block, in the order they were touched.
  const std::vector<int>& touched() const { return touched_; }
  bool hasRow(int pos) const { return pos < static_cast<int>(row_of_.size()) && row_of_[pos] >= 0; }
  const std::vector<Block>& row(int pos) const { return rows_[row_of_[pos]].blocks; }
  const double* rhs(int pos) const { return rows_[row_of_[pos]].b; }
  const double* values() const { return values_.data(); }

 private:
  struct Row {
    int dim = 0;
    double b[kMaxDim] = {};
    std::vector<Block> blocks;
  };
  // The row of `pos`, made when it has none; inline for the row that
  // exists (a batch asks twice per factor), out of line to make one.
  Row& rowFor(int pos, int dim) {
    if (__builtin_expect(pos < static_cast<int>(row_of_.size()) && row_of_[pos] >= 0, 1))
      return rows_[row_of_[pos]];
    return newRow(pos, dim);
  }
  Row& newRow(int pos, int dim);

  std::vector<int> row_of_;  // position -> index into rows_, -1 when absent
  std::vector<int> touched_;
  std::vector<Row> rows_;  // reused between clears (their vectors keep capacity)
  int used_rows_ = 0;
  // The first used_values_ entries are in use; the array only grows, and a
  // block costs no zero-fill (jtj writes all of it).
  PooledArray<double> values_;
  std::size_t used_values_ = 0;
  int newBlock(int size) {
    const std::size_t offset = used_values_;
    used_values_ += size;
    if (__builtin_expect(used_values_ > values_.capacity(), 0)) values_.reserve(used_values_);
    return static_cast<int>(offset);
  }
};

}  // namespace hamal::aprilsam
