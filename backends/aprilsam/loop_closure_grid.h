// LoopClosureGrid: COUNTPOSSIBLELOOPCLOSURENODES of Alg. 3.1 (line 9, the
// n_lc of the time criterion in line 10 and sec. 3.4.4): the nodes within
// R_T (eq. 3.20) of the newest pose, found through a grid of R_T x R_T
// cells so that the count costs the neighbourhood, not the map. A variable
// is filed in the cell of its linearisation point when it arrives and again
// at each batch; the count reads the points as they are then. With a fixed
// n_lc (the default) or no radius nothing is filed: the count never reads
// the cells, and refiling every variable at every batch was a twentieth of
// a robust run that batches at every step.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <unordered_map>
#include <vector>

#include "core/values.h"

namespace hamal::aprilsam {

class LoopClosureGrid {
 public:
  // `radius` is R_T (loop_closure_radius; 0: no grid, no nodes); `n_lc` > 0
  // is a fixed count that the grid is not asked for.
  LoopClosureGrid(double radius, long n_lc) : radius_(radius), n_lc_(n_lc) {}

  // Files variable `v` at its linearisation point `lin` (not when that is
  // not finite).
  void insert(int v, const Values::Entry& lin);
  // Every variable filed again at `lin` (after a batch moved them); the
  // cells keep their capacity.
  void refile(const std::vector<Values::Entry>& lin);
  // n_lc: the fixed count, or the variables other than `newest` within R_T
  // of it at their linearisation points `lin`; 0 without a newest pose.
  long countPossibleLoopClosureNodes(int newest, const std::vector<Values::Entry>& lin) const;
  // Cells held (none when the count is fixed), empty ones included (after a refile at most twice
  // the variables plus 64, and the cells that refile added).
  std::size_t cells() const { return cells_.size(); }

 private:
  long cell(double x, double y) const;
  // Whether the count reads the cells (n_lc = 0 and a radius).
  bool counts() const { return n_lc_ <= 0 && radius_ > 0; }

  double radius_;
  long n_lc_;
  std::unordered_map<long, std::vector<int>> cells_;  // cell -> variables
};

}  // namespace hamal::aprilsam
