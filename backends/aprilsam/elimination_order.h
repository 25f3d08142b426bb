// EliminationOrder: the order in which AprilSAM eliminates its free
// variables, the rows of R (thesis sec. 3.4.3): position p holds variable
// varAt(p), variable v sits at posOf(v), -1 when v is fixed (core/step.h:
// no column in R). The two maps change only together, here: a new variable
// at the end (Alg. 3.1 line 2), a batch's new order (sec. 3.4.3), a top
// re-elimination's permutation (IncrementalCholesky::reorderTop).
#pragma once

#include <algorithm>
#include <vector>

namespace hamal::aprilsam {

class EliminationOrder {
 public:
  // Positions held (R's block rows).
  int size() const { return static_cast<int>(var_at_.size()); }
  int posOf(int v) const { return pos_of_[v]; }
  int varAt(int p) const { return var_at_[p]; }
  // posOf for every variable, as the linearisation reads it.
  const int* positions() const { return pos_of_.data(); }

  // New variable v (the next index): at the end of the order, or without
  // a position when fixed.
  void add(int v, bool fixed) {
    if (fixed) {
      pos_of_.push_back(-1);
      return;
    }
    pos_of_.push_back(size());
    var_at_.push_back(v);
  }
  // A batch's order: `order` lists the free variables, first eliminated
  // first; the others have no position.
  void layOut(const std::vector<int>& order) {
    var_at_ = order;
    std::fill(pos_of_.begin(), pos_of_.end(), -1);
    for (int p = 0; p < size(); ++p) pos_of_[var_at_[p]] = p;
  }
  // Position p's variable moves to new_pos[p] (a permutation of the
  // positions).
  void permute(const std::vector<int>& new_pos) {
    const std::vector<int> old_var_at = var_at_;
    for (int p = 0; p < size(); ++p) {
      var_at_[new_pos[p]] = old_var_at[p];
      pos_of_[old_var_at[p]] = new_pos[p];
    }
  }

 private:
  std::vector<int> pos_of_;  // v -> position, -1 if fixed
  std::vector<int> var_at_;  // position -> v
};

}  // namespace hamal::aprilsam
