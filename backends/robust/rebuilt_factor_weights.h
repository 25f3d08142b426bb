// RebuiltFactorWeights: FactorWeights (core/factor_weights.h) for any
// back-end, by making it anew. Graduated non-convexity
// (graduated_non_convexity.h) needs to change the weights of some factors
// between solves; a back-end that does not offer FactorWeights is wrapped in
// this adapter, which forwards steps as they come while no weight differs
// from what the back-end holds, and otherwise makes a fresh back-end and
// hands it everything received so far as one step: the current estimate as
// initial values, the fixed variables, each factor of weight 1 as it is, one
// of weight w in (0, 1) as a WeightedFactor, and none of weight 0. That is
// exact for every back-end, at the cost of a batch per change of weights;
// a back-end that keeps linearisations between updates should offer
// FactorWeights itself (aprilsam does).
#pragma once

#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

#include "core/backend.h"
#include "core/factor_weights.h"

namespace hamal::robust {

class RebuiltFactorWeights : public Backend, public FactorWeights {
 public:
  // `inner` is the first back-end (made by `make`, which makes the next).
  RebuiltFactorWeights(std::function<std::unique_ptr<Backend>()> make,
                       std::unique_ptr<Backend> inner);

  UpdateResult update(const Step& step) override;
  // Stable: entries keep their addresses across rebuilds.
  const Values& estimate() const override { return estimate_; }

  void setFactorWeight(const Factor* factor, double weight) override;
  double factorWeight(const Factor* factor) const override;

  // Back-ends made so far (1 before any change of weights).
  long rebuilds() const { return rebuilds_; }

 private:
  std::function<std::unique_ptr<Backend>()> make_;
  std::unique_ptr<Backend> inner_;
  Values estimate_;
  std::vector<Key> fixed_;
  std::vector<FactorPtr> factors_;
  std::unordered_map<const Factor*, std::size_t> index_;
  std::vector<double> weight_;       // per factor, what the caller set
  std::vector<double> held_weight_;  // per factor, what inner_ was given
  bool dirty_ = false;               // some weight_ != held_weight_
  long rebuilds_ = 1;
};

}  // namespace hamal::robust
