// VariableTable: see variable_table.h (thesis sec. 3.3, Alg. 3.1).
#include "backends/aprilsam/variable_table.h"

namespace hamal::aprilsam {

int VariableTable::add(Key key, const Values::Entry& guess, bool fixed) {
  const int v = size();
  index_.emplace(key, v);
  keys_.push_back(key);
  dims_.push_back(dimension(guess.type));
  fixed_.push_back(fixed);
  lin_.push_back(guess);
  estimate_.insertEntry(key, guess);
  est_.push_back(estimate_.data(key));
  if (guess.type == VariableType::kPose2) newest_pose_ = v;
  return v;
}

Eigen::Vector2d VariableTable::orderingPosition(int v) const {
  // A non-finite location is put far away, so the min-heap's distance test
  // (eq. 3.20) neither reads NaN nor counts it near the newest pose.
  const Eigen::Vector2d p(lin_[v].data[0], lin_[v].data[1]);
  return p.allFinite() ? p : Eigen::Vector2d::Constant(1e300);
}

}  // namespace hamal::aprilsam
