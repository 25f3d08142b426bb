// RelinearizationSet: L of Alg. 3.1 (thesis sec. 3.4.4), the variables whose
// change |dx_v|_inf reaches delta_T, and the norm ||dx|| of the whole change:
// what the update policy's first two criteria read (update_policy.h). Both
// are kept as each variable's dx changes, so a step costs its changed
// variables, not the map.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace hamal::aprilsam {

class RelinearizationSet {
 public:
  explicit RelinearizationSet(double delta_t) : delta_t_(delta_t) {}

  // A new variable, with no change yet.
  void add() {
    moved_.push_back(0);
    dx_sq_of_.push_back(0);
  }
  // Variable v's dx is now of size |dx|^2 = sq, |dx|_inf = inf.
  void record(int v, double sq, double inf) {
    dx_sq_ += sq - dx_sq_of_[v];
    dx_sq_of_[v] = sq;
    const char m = !(inf < delta_t_);  // NaN counts as moved
    moved_count_ += m - moved_[v];
    moved_[v] = m;
  }
  // No variable has changed (a batch starts from dx = 0).
  void clear() {
    dx_sq_ = 0;
    moved_count_ = 0;
    std::fill(dx_sq_of_.begin(), dx_sq_of_.end(), 0.0);
    std::fill(moved_.begin(), moved_.end(), 0);
  }

  long size() const { return moved_count_; }                          // |L|
  double dxNorm() const { return std::sqrt(std::max(dx_sq_, 0.0)); }  // ||dx||
  bool moved(int v) const { return moved_[v] != 0; }                  // v in L
  double dxSquared(int v) const { return dx_sq_of_[v]; }              // |dx_v|^2

 private:
  double delta_t_;  // delta_T
  std::vector<char> moved_;
  std::vector<double> dx_sq_of_;
  long moved_count_ = 0;
  double dx_sq_ = 0;  // kept as dx changes
};

}  // namespace hamal::aprilsam
