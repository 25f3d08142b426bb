// NoiseScale: the doubt rule "the noise the answer shows" (backends/robust/DOUBT.md,
// docs/ROBUST_DOUBT_RULES.md "The noise scale the answer shows"), for the truncated
// objective check (truncated_objective_check.h).
//
// c2 is a chi2 quantile in the units of the graph's stated informations.
// Where they overstate the noise by a wide factor, a false group can bend the
// map and still leave every closure it brings within c2, so the cheaper
// alternative at c2 finds nothing. The answer itself tells how noisy the data
// are: the a-posteriori variance factor of least-squares adjustment
// (geodesy's sigma0^2), the chi2 of the factors it keeps over their
// redundancy. A variance factor far below 1 says the stated noise is
// overstated by that factor, and the 0.99 quantile of the residuals the data
// show is c2 scaled by it: the alternative from the answer is solved again
// there.
#pragma once

#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/key.h"
#include "core/values.h"

namespace hamal::robust {

// The variance factor sigma0^2 = chi2 / redundancy of the factors an answer
// keeps (every known inlier, each candidate within its c2 there). The
// redundancy is their residual rows less the map's free parameters: the
// variables they touch, less the fixed ones, less the plane's 3 rigid
// motions per connected part held by no fixed variable or unary factor
// (its gauge).
struct NoiseScale {
  double chi2 = 0;
  double redundancy = 0;
  double factor() const { return redundancy > 0 ? chi2 / redundancy : 1; }
};
// Throws hamal::Error when a factor does not evaluate at `values` or c2 and
// candidates differ in number.
NoiseScale aPosterioriVarianceFactor(const std::vector<FactorPtr>& inliers,
                                     const std::vector<FactorPtr>& candidates,
                                     const std::vector<double>& c2, const std::vector<Key>& fixed,
                                     const Values& values);

// The rule applies when the variance factor is below this: the stated
// variance is at least twice the one the answer shows. A graph whose
// informations are its noise's shows chi2_r / r, below 0.5 with a chance
// of about 1e-5 at a redundancy r of 100 (the least the rule takes);
// hamal_generate's worlds, which state their noise, show 0.86-1.07 at their
// optimum. The false closures an answer keeps only raise the factor (they
// bend the map, the inliers pay for it), so the bound sits well above an
// overstated graph's own factor (M3500's), below every stated world
// (docs/ROBUST_DOUBT_RULES.md has the figures).
inline constexpr double kOverstatedNoise = 0.5;
// Below this redundancy the factor is the spread of a few residuals, no
// scale of the graph's noise: the rule does not apply.
inline constexpr double kMinRedundancy = 100;

// Whether the rule applies to `scale`.
bool noiseOverstated(const NoiseScale& scale);

// The rule's verdict: at c2 scaled by the variance factor (`scaled_c2`),
// the alternative's truncated objective `alternative` below the answer's
// `objective` by more than `margin`, the stated c2 (the plain rule's): the
// scaled c2 says which closures fit, but an alternative to a right answer
// drops true closures a little beyond it for a gain of a few scaled c2, so
// the evidence asked for stays what one decision swings at the stated c2.
// kUncertain naming the scale and the figures; else ok.
Status noiseScaleDoubt(const NoiseScale& scale, double scaled_c2, double objective,
                       double alternative, double margin);

}  // namespace hamal::robust
