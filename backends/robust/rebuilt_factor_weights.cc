// RebuiltFactorWeights: see rebuilt_factor_weights.h.
#include "backends/robust/rebuilt_factor_weights.h"

#include <cmath>
#include <string>

#include "backends/robust/weighted_factor.h"
#include "core/error.h"

namespace hamal::robust {

RebuiltFactorWeights::RebuiltFactorWeights(std::function<std::unique_ptr<Backend>()> make,
                                           std::unique_ptr<Backend> inner)
    : make_(std::move(make)), inner_(std::move(inner)) {
  if (!inner_) throw Error("factor weights: no back-end to wrap");
}

void RebuiltFactorWeights::setFactorWeight(const Factor* factor, double weight) {
  const auto it = index_.find(factor);
  if (it == index_.end()) throw Error("factor weights: the back-end does not hold that factor");
  if (!(weight >= 0) || !std::isfinite(weight))
    throw Error("factor weights: weight " + std::to_string(weight) +
                " is not a finite number >= 0");
  weight_[it->second] = weight;
  if (weight != held_weight_[it->second]) dirty_ = true;
}

double RebuiltFactorWeights::factorWeight(const Factor* factor) const {
  const auto it = index_.find(factor);
  if (it == index_.end()) throw Error("factor weights: the back-end does not hold that factor");
  return weight_[it->second];
}

UpdateResult RebuiltFactorWeights::update(const Step& step) {
  UpdateResult result;
  if (!dirty_) {
    result = inner_->update(step);  // throws on bad input, before anything here changes
  } else {
    checkStep(step, estimate_, "factor weights");
    Step all;
    all.index = step.index;
    for (const auto& [key, entry] : inner_->estimate()) all.new_values.insertEntry(key, entry);
    for (const auto& [key, entry] : step.new_values) all.new_values.insertEntry(key, entry);
    all.fixed = fixed_;
    all.fixed.insert(all.fixed.end(), step.fixed.begin(), step.fixed.end());
    for (std::size_t f = 0; f < factors_.size(); ++f) {
      if (weight_[f] == 0) continue;
      all.new_factors.push_back(weight_[f] == 1
                                    ? factors_[f]
                                    : std::make_shared<WeightedFactor>(factors_[f], weight_[f]));
    }
    all.new_factors.insert(all.new_factors.end(), step.new_factors.begin(), step.new_factors.end());
    std::unique_ptr<Backend> fresh = make_();
    if (!fresh) throw Error("factor weights: the back-end could not be made again");
    result = fresh->update(all);
    inner_ = std::move(fresh);
    ++rebuilds_;
    held_weight_ = weight_;
    dirty_ = false;
    result.reason += "; made anew for new factor weights";
  }
  fixed_.insert(fixed_.end(), step.fixed.begin(), step.fixed.end());
  for (const FactorPtr& f : step.new_factors) {
    index_.emplace(f.get(), factors_.size());
    factors_.push_back(f);
    weight_.push_back(1);
    held_weight_.push_back(1);
  }
  // In place, so that pointers into estimate_ stay valid.
  for (const auto& [key, entry] : inner_->estimate()) estimate_.setEntry(key, entry);
  return result;
}

}  // namespace hamal::robust
