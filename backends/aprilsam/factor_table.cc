// FactorTable: see factor_table.h (thesis sec. 3.3, Alg. 3.1).
#include "backends/aprilsam/factor_table.h"

namespace hamal::aprilsam {

int FactorTable::add(const FactorPtr& factor, const VariableTable& vars) {
  const int f = static_cast<int>(factors_.size());
  for (const Key& key : factor->keys()) {
    const int v = vars.at(key);
    vars_.push_back(v);
    of_var_[v].push_back(f);
  }
  factors_.push_back(factor);
  weight_.push_back(1);
  lin_weight_.push_back(1);
  index_.emplace(factor.get(), f);
  begin_.push_back(static_cast<int>(vars_.size()));
  return f;
}

}  // namespace hamal::aprilsam
