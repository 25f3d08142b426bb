// WeightedFactor: a factor whose term of the objective is w times another
// factor's (w |r|^2: its whitened residual and Jacobians scaled by sqrt(w)).
// It is how RebuiltFactorWeights hands a weighted least-squares problem of
// graduated non-convexity (graduated_non_convexity.h) to a back-end that has
// no weights of its own: the weight is fixed when the wrapper is made, so a
// back-end that caches anything about its factors sees a plain factor.
//
// It writes itself as the factor it wraps (a weight is a state of the
// solver, not part of the measurement) and predicts as it does.
#pragma once

#include "core/factor.h"
#include "core/variable_prediction.h"

namespace hamal::robust {

class WeightedFactor : public Factor, public VariablePrediction {
 public:
  // Throws hamal::Error for a null factor, a weight that is not finite and
  // > 0 (a weight of 0 is the factor left out), or a factor with a loss or
  // modes (their terms are not |r|^2).
  WeightedFactor(FactorPtr inner, double weight);

  const FactorPtr& inner() const { return inner_; }
  double weight() const { return weight_; }

  std::string tag() const override { return inner_->tag(); }
  void writeFields(std::ostream& os) const override { inner_->writeFields(os); }
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override {
    return predictVariable(*inner_, unknown, known, guess);
  }

 private:
  FactorPtr inner_;
  double weight_;
};

}  // namespace hamal::robust
