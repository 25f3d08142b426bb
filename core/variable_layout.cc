// VariableLayout: see variable_layout.h.
#include "core/variable_layout.h"

#include <set>

#include "core/error.h"

namespace hamal {

bool VariableLayout::add(const Step& step) {
  const std::set<Key> fixed(step.fixed.begin(), step.fixed.end());
  for (Key key : step.new_values.keys()) {
    const int tangent = hamal::dimension(step.new_values.type(key));
    index_.emplace(key, size());
    keys_.push_back(key);
    width_.push_back(fixed.count(key) ? 0 : tangent);
    column_.push_back(dimension_);
    dimension_ += width_.back();
  }
  bool moved = false;
  for (Key key : step.fixed) {
    const int i = index(key);
    if (width_[i] == 0) continue;
    width_[i] = 0;
    moved = true;
  }
  if (moved) relayout();
  return moved;
}

long VariableLayout::dimensionAfter(const Step& step) const {
  const std::set<Key> fixed(step.fixed.begin(), step.fixed.end());
  long after = dimension_;
  for (const auto& [key, entry] : step.new_values)
    if (!fixed.count(key)) after += hamal::dimension(entry.type);
  for (Key key : fixed) {
    const auto it = index_.find(key);
    if (it != index_.end()) after -= width_[it->second];
  }
  return after;
}

int VariableLayout::index(Key key) const {
  const auto it = index_.find(key);
  if (it == index_.end()) throw Error("VariableLayout: unknown variable " + key.str());
  return it->second;
}

int VariableLayout::variableOfColumn(long column) const {
  // The last variable that starts at or before `column` and has a width.
  const auto it = std::upper_bound(column_.begin(), column_.end(), column);
  int i = static_cast<int>(it - column_.begin()) - 1;
  while (i > 0 && width_[i] == 0) --i;
  return i;
}

void VariableLayout::retract(Values* values, const double* dx) const {
  for (int i = 0; i < size(); ++i)
    if (width_[i] > 0) values->retract(keys_[i], dx + column_[i]);
}

void VariableLayout::relayout() {
  dimension_ = 0;
  for (int i = 0; i < size(); ++i) {
    column_[i] = dimension_;
    dimension_ += width_[i];
  }
}

}  // namespace hamal
