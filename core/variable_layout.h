// VariableLayout: where each variable of a back-end's system sits (thesis
// sec. 2.2.4: the columns of A, and of A^T A, one block per variable).
//
// Variables are numbered in order of arrival (a step's new variables in key
// order, core/values.h), and each free variable owns a run of scalar columns
// as wide as its tangent space, laid out in that order. A fixed variable
// (Step::fixed) keeps its number and has no column: a width of 0. Fixing a
// known variable lays every column after it out again, which add() reports,
// so a back-end knows when its pattern moved.
//
// Every back-end needs this bookkeeping; one copy keeps the fixed-variable
// rule (core/step.h) the same in all of them.
#pragma once

#include <algorithm>
#include <unordered_map>
#include <vector>

#include "core/key.h"
#include "core/step.h"
#include "core/values.h"

namespace hamal {

class VariableLayout {
 public:
  // Records a step that checkStep (core/step.h) accepted: its new variables,
  // then the variables it fixes. Returns true when a known variable became
  // fixed, so that columns of earlier variables moved.
  bool add(const Step& step);
  // The number of scalar columns there would be after `step` (not recorded).
  long dimensionAfter(const Step& step) const;

  int size() const { return static_cast<int>(keys_.size()); }
  bool contains(Key key) const { return index_.count(key) != 0; }
  // The number of a variable; throws hamal::Error when it is unknown.
  int index(Key key) const;
  Key key(int i) const { return keys_[i]; }
  bool fixed(int i) const { return width_[i] == 0; }
  // Scalar columns of variable i: its tangent dimension, 0 when fixed.
  int width(int i) const { return width_[i]; }
  // The first scalar column of variable i (where the next free one would
  // start, when it is fixed).
  long column(int i) const { return column_[i]; }
  // Scalar columns in all.
  long dimension() const { return dimension_; }
  // The variable that owns scalar column `column` (0 <= column < dimension()).
  int variableOfColumn(long column) const;

  // values <- values [+] dx for every free variable, dx in this layout.
  void retract(Values* values, const double* dx) const;

 private:
  void relayout();

  std::vector<Key> keys_;
  std::vector<int> width_;
  std::vector<long> column_;
  std::unordered_map<Key, int> index_;
  long dimension_ = 0;
};

}  // namespace hamal
