// WeightedFactor: see weighted_factor.h.
#include "backends/robust/weighted_factor.h"

#include <cmath>
#include <memory>

#include "core/error.h"
#include "core/multi_modal.h"

namespace hamal::robust {

namespace {

// The inner cost function with its residual and Jacobians scaled by sqrt(w).
class ScaledCost : public ceres::CostFunction {
 public:
  ScaledCost(const ceres::CostFunction* inner, double weight)
      : inner_(inner), scale_(std::sqrt(weight)) {
    set_num_residuals(inner->num_residuals());
    *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    if (!inner_->Evaluate(parameters, residuals, jacobians)) return false;
    const int m = num_residuals();
    for (int i = 0; i < m; ++i) residuals[i] *= scale_;
    if (jacobians) {
      const auto& sizes = parameter_block_sizes();
      for (std::size_t k = 0; k < sizes.size(); ++k)
        if (jacobians[k])
          for (int i = 0; i < m * sizes[k]; ++i) jacobians[k][i] *= scale_;
    }
    return true;
  }

 private:
  const ceres::CostFunction* inner_;
  double scale_;
};

const FactorPtr& checked(const FactorPtr& inner, double weight) {
  if (!inner) throw Error("weighted factor: no factor to weigh");
  if (!(weight > 0) || !std::isfinite(weight))
    throw Error("weighted factor: weight " + std::to_string(weight) + " on " + inner->tag() +
                " is not a finite number > 0");
  if (inner->lossFunction() || asMultiModal(*inner))
    throw Error("weighted factor: " + inner->tag() +
                " carries a loss or modes; only a plain |r|^2 term can be weighted");
  return inner;
}

}  // namespace

WeightedFactor::WeightedFactor(FactorPtr inner, double weight)
    : Factor(checked(inner, weight)->keys(),
             std::make_unique<ScaledCost>(checked(inner, weight)->costFunction(), weight)),
      inner_(std::move(inner)),
      weight_(weight) {}

}  // namespace hamal::robust
