// The deterministic cost of a Cholesky factorisation, which AprilSAM's
// update policy (thesis sec. 3.4.4, Alg. 3.1 line 10) can compare instead
// of measured run times.
//
// The thesis compares RUNTIME(incremental) x n_lc with RUNTIME(batch), read
// from the wall clock; so does its authors' code, and its chi2 on M3500
// varies from 137.91 to 139.83 between runs of the same input (docs/PROTOCOL.md)
// because the batch decisions follow the machine's load. The flop count of
// the factorisation is what the run time of a sparse Cholesky is made of,
// is a pure function of the structure and the ordering, and makes every run
// of a configuration reproducible.
#pragma once

#include <vector>

namespace hamal::aprilsam {

// The standard estimate of the work of a sparse Cholesky factorisation:
// sum over the columns of L of colcount^2 (colcount counts the diagonal).
// Pass the counts of only the columns an incremental update recomputes to
// get that update's cost. Counts of blocks give the cost in blocks; the
// caller scales by the block sizes if it wants scalar flops.
double choleskyFlops(const std::vector<long>& column_counts);

// Column counts of the Cholesky factor L of a node graph (nonzeros per
// column, diagonal included) when nodes are eliminated in `order`
// (order[k] = node eliminated k-th); result[k] belongs to order[k]. Uses the
// elimination tree and row subtrees, O(nnz(L)) time. `adjacency` is read as
// A + A^T (self loops ignored). Throws hamal::Error when `order` is not a
// permutation of the nodes or an id is out of range.
std::vector<long> choleskyColumnCounts(const std::vector<std::vector<int>>& adjacency,
                                       const std::vector<int>& order);

}  // namespace hamal::aprilsam
