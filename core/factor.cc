// Factor: see factor.h.
#include "core/factor.h"

#include <limits>

#include "core/error.h"

namespace hamal {

Factor::Factor(std::vector<Key> keys, std::unique_ptr<ceres::CostFunction> cost,
               std::shared_ptr<ceres::LossFunction> loss)
    : keys_(std::move(keys)), cost_(std::move(cost)), loss_(std::move(loss)) {
  if (!cost_) throw Error("Factor: no cost function");
  if (cost_->parameter_block_sizes().size() != keys_.size())
    throw Error("Factor: the cost function has " +
                std::to_string(cost_->parameter_block_sizes().size()) + " parameter blocks for " +
                std::to_string(keys_.size()) + " keys");
}

Factor::~Factor() = default;

bool Factor::predict(Key, const Values&, Values::Entry*) const { return false; }

bool Factor::hasModes() const { return false; }

int Factor::mode(const double* const*) const { return 0; }

double Factor::modeInformationScale(int) const { return 1.0; }

const Factor* Factor::modeComponent(int) const { return nullptr; }

bool Factor::isNullHypothesisPair() const { return false; }

double Factor::logDetInformation() const { return std::numeric_limits<double>::quiet_NaN(); }

std::optional<Factor::RelativePose> Factor::relativePose() const { return std::nullopt; }

bool Factor::evaluate(const Values& values, double* residual) const {
  std::vector<const double*> params;
  params.reserve(keys_.size());
  for (Key k : keys_) params.push_back(values.data(k));
  return cost_->Evaluate(params.data(), residual, nullptr);
}

double Factor::chi2(const Values& values) const {
  std::vector<double> r(residualDim());
  if (!evaluate(values, r.data())) return std::numeric_limits<double>::infinity();
  double s = 0.0;
  for (double v : r) s += v * v;
  return s;
}

}  // namespace hamal
