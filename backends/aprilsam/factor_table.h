// FactorTable: the factors of AprilSAM's graph G (thesis sec. 3.3, Alg.
// 3.1), each with the variables it touches (by index in the VariableTable),
// the factors on each variable, and its weight (core/factor_weights.h) next
// to the weight R holds it with: R keeps each factor at the weight it had
// when it was linearised, and the factors whose two differ are listed, so
// the next update takes the difference out and in (reweighted()).
#pragma once

#include <cstddef>
#include <unordered_map>
#include <vector>

#include "backends/aprilsam/variable_table.h"
#include "core/factor.h"

namespace hamal::aprilsam {

// A run of variable indices (a factor's variables).
struct IndexRange {
  const int* first;
  const int* last;
  const int* begin() const { return first; }
  const int* end() const { return last; }
  int size() const { return static_cast<int>(last - first); }
  int operator[](int k) const { return first[k]; }
};

class FactorTable {
 public:
  FactorTable() { begin_.push_back(0); }

  // A new variable, with no factor yet.
  void addVariable() { of_var_.emplace_back(); }
  // A new factor on variables `vars` holds, at weight 1; its index f.
  int add(const FactorPtr& factor, const VariableTable& vars);

  std::size_t size() const { return factors_.size(); }
  const FactorPtr& factor(std::size_t f) const { return factors_[f]; }
  const std::vector<FactorPtr>& all() const { return factors_; }
  IndexRange vars(std::size_t f) const {
    return {vars_.data() + begin_[f], vars_.data() + begin_[f + 1]};
  }
  const std::vector<int>& factorsOf(int v) const { return of_var_[v]; }
  // f's index, -1 when the table does not hold `factor`.
  int find(const Factor* factor) const {
    const auto it = index_.find(factor);
    return it == index_.end() ? -1 : it->second;
  }

  double weight(std::size_t f) const { return weight_[f]; }
  double linWeight(std::size_t f) const { return lin_weight_[f]; }
  void setWeight(int f, double weight) {
    if (weight_[f] == weight) return;
    if (weight_[f] == lin_weight_[f]) reweighted_.push_back(f);
    weight_[f] = weight;
  }
  // R holds f at its weight from now on (f is linearised); that weight.
  double holdAtWeight(std::size_t f) { return lin_weight_[f] = weight_[f]; }
  // The factors whose weight may differ from the one R holds.
  const std::vector<int>& reweighted() const { return reweighted_; }
  void clearReweighted() { reweighted_.clear(); }

 private:
  std::vector<FactorPtr> factors_;
  std::vector<int> vars_;   // flat: the variables of each factor
  std::vector<int> begin_;  // size() + 1 offsets into vars_
  std::vector<std::vector<int>> of_var_;
  std::unordered_map<const Factor*, int> index_;
  std::vector<double> weight_, lin_weight_;
  std::vector<int> reweighted_;
};

}  // namespace hamal::aprilsam
