// VariableTable: the variables of AprilSAM's graph G (thesis sec. 3.3, Alg.
// 3.1), each with its key, its dimension, whether it is fixed (core/step.h),
// its linearisation point (mu of eq. 3.3) and its estimate lin_point [+] dx.
//
// It owns the estimate (a Values) and reads and writes it through a pointer
// per variable into its storage (stable: unordered_map nodes), so the hot
// loops (the retraction after each solve, the gathering of a factor's
// parameters) never hash a key. Index v is the order of arrival.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "core/key.h"
#include "core/pose2.h"
#include "core/values.h"

namespace hamal::aprilsam {

class VariableTable {
 public:
  VariableTable() = default;
  VariableTable(const VariableTable&) = delete;  // est_ points into estimate_
  VariableTable& operator=(const VariableTable&) = delete;

  // A new variable at its initial guess; its index v.
  int add(Key key, const Values::Entry& guess, bool fixed);

  int size() const { return static_cast<int>(keys_.size()); }
  Key key(int v) const { return keys_[v]; }
  const std::vector<Key>& keys() const { return keys_; }
  int dim(int v) const { return dims_[v]; }
  bool fixed(int v) const { return fixed_[v] != 0; }
  // Variable v is fixed from now on, held at its estimate.
  void fix(int v) {
    fixed_[v] = 1;
    moveLinearizationPoint(v);
  }
  // v's index, -1 when the table does not hold `key`; at() throws then.
  int find(Key key) const {
    const auto it = index_.find(key);
    return it == index_.end() ? -1 : it->second;
  }
  int at(Key key) const { return index_.at(key); }
  // The pose that arrived last (-1: none), the newest of eq. 3.20.
  int newestPose() const { return newest_pose_; }

  const Values::Entry& lin(int v) const { return lin_[v]; }
  const std::vector<Values::Entry>& linPoints() const { return lin_; }
  const double* est(int v) const { return est_[v]; }
  const Values& estimate() const { return estimate_; }

  // UPDATELINEARIZATIONPOINT (Alg. 3.1 line 12) of variable v.
  void moveLinearizationPoint(int v) {
    for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
  }
  // The estimate of v back at its linearisation point.
  void resetEstimate(int v) {
    for (int t = 0; t < dims_[v]; ++t) est_[v][t] = lin_[v].data[t];
  }
  // estimate = lin_point [+] dx (Alg. 3.1 lines 5-8, Values::retract's
  // convention: plain addition, a Pose2's angle wrapped); the size of dx in
  // *sq = |dx|^2 and *inf = |dx|_inf, which the update policy reads.
  void retract(int v, const double* dx, double* sq, double* inf) {
    double s = 0, m = 0;
    double* est = est_[v];
    const double* lin = lin_[v].data.data();
    const int d = dims_[v];
    for (int t = 0; t < d; ++t) {
      s += dx[t] * dx[t];
      m = std::max(m, std::fabs(dx[t]));
      est[t] = lin[t] + dx[t];
    }
    if (lin_[v].type == VariableType::kPose2) est[2] = wrapAngle(est[2]);
    *sq = s;
    *inf = m;
  }
  // Whether v's estimate is finite.
  bool estimateIsFinite(int v) const {
    bool finite = true;
    for (int t = 0; t < dims_[v]; ++t) finite &= std::isfinite(est_[v][t]);
    return finite;
  }
  // Variable v's place for the orderings' input (eq. 3.20's distance): its
  // linearisation point, far away when not finite.
  Eigen::Vector2d orderingPosition(int v) const;

 private:
  std::vector<Key> keys_;
  std::vector<int> dims_;
  std::vector<char> fixed_;  // held at its value, no position (core/step.h)
  std::vector<Values::Entry> lin_;
  std::vector<double*> est_;  // into estimate_
  std::unordered_map<Key, int> index_;
  Values estimate_;
  int newest_pose_ = -1;
};

}  // namespace hamal::aprilsam
