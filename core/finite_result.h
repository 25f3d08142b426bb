// A non-finite result is never ok: the checks a back-end runs on the cost and
// the estimate it is about to report (docs/ARCHITECTURE.md, "Errors"; Ceres likewise
// ends a solve as FAILURE when its cost is not finite). Each returns a
// numerical-failure Status that names the culprit, a variable or a factor,
// so the user learns where to look, and an ok Status otherwise.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/values.h"

namespace hamal {

// The first variable of `keys` (all of `values` when `keys` is empty) with a
// component that is NaN or infinite.
Status finiteEstimateStatus(const Values& values, const std::string& backend,
                            const std::vector<Key>& keys = {});

// When `cost` is not finite: names the factor whose chi2 at `values` is not
// finite or, when each is finite and only their sum overflows, the largest.
Status finiteCostStatus(double cost, const std::vector<FactorPtr>& factors, const Values& values,
                        const std::string& backend);

// A factor's whitened residual w is computed with a relative rounding of at
// least machine epsilon, so once |w| > 1/eps (chi2 above 1/eps^2, about
// 2e31) the rounding alone exceeds one standard deviation: no estimate is
// resolved against that factor, whatever the solver reports.
constexpr double kMaxResolvableChi2 =
    1.0 / (std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon());

// The cost of `factors` at `values` (all their variables must be known),
// refused as finiteCostStatus does when it is not finite, and when one
// factor's chi2 exceeds kMaxResolvableChi2, naming it. A back-end that
// reports a converged estimate without factorising a system of its own
// (ceres) runs this on its final estimate.
Status resolvableCostStatus(const std::vector<FactorPtr>& factors, const Values& values,
                            const std::string& backend);

}  // namespace hamal
