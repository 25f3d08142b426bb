// Finite results: see finite_result.h.
#include "core/finite_result.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace hamal {

namespace {

std::string keyList(const std::vector<Key>& keys) {
  std::string out;
  for (Key k : keys) out += (out.empty() ? "" : ", ") + k.str();
  return out;
}

std::string number(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

}  // namespace

Status finiteEstimateStatus(const Values& values, const std::string& backend,
                            const std::vector<Key>& keys) {
  const std::vector<Key> all = keys.empty() ? values.keys() : keys;
  for (Key k : all) {
    if (!values.contains(k)) continue;
    const double* x = values.data(k);
    for (int i = 0; i < values.dim(k); ++i)
      if (!std::isfinite(x[i]))
        return Status::numericalFailure(backend + ": the estimate of " + k.str() +
                                            " is not finite (component " + std::to_string(i) +
                                            " is " + number(x[i]) + ")",
                                        {k});
  }
  return {};
}

Status finiteCostStatus(double cost, const std::vector<FactorPtr>& factors, const Values& values,
                        const std::string& backend) {
  if (std::isfinite(cost)) return {};
  const Factor* worst = nullptr;
  double worst_chi2 = -1;
  for (const FactorPtr& f : factors) {
    bool known = true;
    for (Key k : f->keys()) known = known && values.contains(k);
    if (!known) continue;
    const double c = f->chi2(values);
    if (!std::isfinite(c)) {
      worst = f.get();
      worst_chi2 = c;
      break;
    }
    if (c > worst_chi2) {
      worst = f.get();
      worst_chi2 = c;
    }
  }
  if (!worst)
    return Status::numericalFailure(backend + ": the cost is not finite (" + number(cost) + ")");
  return Status::numericalFailure(
      backend + ": the cost is not finite (" + number(cost) + "); factor " + worst->tag() + " on " +
          keyList(worst->keys()) + " has chi2 " + number(worst_chi2) +
          (std::isfinite(worst_chi2) ? ", the largest: the sum overflows" : "") +
          " (is its measurement or information absurdly large?)",
      worst->keys());
}

Status resolvableCostStatus(const std::vector<FactorPtr>& factors, const Values& values,
                            const std::string& backend) {
  double cost = 0;
  const Factor* worst = nullptr;
  double worst_chi2 = -1;
  for (const FactorPtr& f : factors) {
    const double c = f->chi2(values);
    cost += c;
    if (c > worst_chi2) {
      worst = f.get();
      worst_chi2 = c;
    }
  }
  if (!std::isfinite(cost)) return finiteCostStatus(cost, factors, values, backend);
  if (!worst || worst_chi2 <= kMaxResolvableChi2) return {};
  return Status::numericalFailure(
      backend + ": factor " + worst->tag() + " on " + keyList(worst->keys()) + " has chi2 " +
          number(worst_chi2) + " at the estimate, a residual beyond 1/eps (" +
          number(1 / std::numeric_limits<double>::epsilon()) +
          ") standard deviations: its rounding alone exceeds one, so the estimate is not "
          "resolved (is its measurement or information absurdly large?)",
      worst->keys());
}

}  // namespace hamal
