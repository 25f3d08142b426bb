// BackendKit: see backend_kit.h.
#include "core/backend_kit.h"

#include "core/finite_result.h"
#include "core/gauge_freedom.h"
#include "core/metrics.h"

namespace hamal {

bool BackendKit::admit(const Step& step, const std::function<void(const Step&)>& refuse) {
  checkStep(step, estimate_, name_);
  if (refuse) refuse(step);
  for (const auto& [key, entry] : step.new_values) estimate_.insertEntry(key, entry);
  factors_.insert(factors_.end(), step.new_factors.begin(), step.new_factors.end());
  return layout_.add(step);
}

double BackendKit::cost() const { return chi2(factors_, estimate_); }

Status BackendKit::finiteStatus() const {
  const Status estimate = finiteEstimateStatus(estimate_, name_);
  if (!estimate.ok()) return estimate;
  return finiteCostStatus(cost(), factors_, estimate_, name_);
}

Status BackendKit::gaugeStatus() const {
  std::vector<Key> keys, fixed;
  keys.reserve(layout_.size());
  for (int i = 0; i < layout_.size(); ++i) {
    keys.push_back(layout_.key(i));
    if (layout_.fixed(i)) fixed.push_back(layout_.key(i));
  }
  return gaugeFreedomStatus(name_, keys, factors_, fixed);
}

}  // namespace hamal
