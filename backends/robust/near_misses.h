// NearMisses: whether the map refutes the loop closures it rejects, the
// evidence the rule "most closures rejected" (answer_doubt.h) weighs before
// it doubts an answer. Robust estimation over a pose graph (thesis sec.
// 2.4, truncated least squares as GNC minimises it: docs/ROBUST_RULES.md).
//
// Why. More rejected closures than accepted ones is no doubt in itself: a
// map that refutes each rejected closure by a wide margin (kitti_02 + 100:
// every false closure hundreds of c2 beyond its own test) would refute a
// false closure that came in among the accepted just as clearly. What
// makes a high share dangerous is a map too loose to refute them: where the
// rejected closures crowd the edge of the acceptance region, others of
// their kind landed inside it and were accepted (SE-Sync's MIT + 100, 20
// true closures on 808 poses: rejected ones within 2-5 c2). And a map
// whose confidence rests on one closure nothing else tests: a false
// closure that holds a direction of the map alone bends it freely, and the
// bent map then refutes the true closures it moved away from (kitti_05 +
// 1000 random s2: one false closure at leverage 0.99994, 16 true closures
// refuted, 2.2 m).
//
// The test of each rejected closure is the one truncated least squares
// itself applies to a closure it might add: its residual r against the map
// without it, whitened by S = I + G (its own noise plus the map's
// uncertainty of the relative pose it measures, G = J H^-1 J^T of the
// whitened Jacobians: FactorWeights::residualCovariance). In linear least
// squares k c2 = r^T S^-1 r is exactly what accepting it would add to the
// cost, so k > 1 for a closure rejected at a TLS minimum.
//
// The estimate. Outliers of a closure's kind spread over the space of its
// whitened innovation; if their density is about even on the scale of the
// nearest ones, the acceptance ball (radius sqrt(c2), dimension d) holds
// k^(-d/2) of the ball through a rejected closure at k c2. Each rejected
// closure so stands for min(1, k^(-d/2)) closures accepted by chance, and
// their sum is the expected number of false closures among the accepted.
// A rejected closure at k <= 1 (TLS would have gained by accepting it: a
// local minimum) counts 1. The density is extrapolated from the nearest
// closures, so the estimate is good to a factor of a few, not better: the
// rule that reads it has a threshold with that much room (answer_doubt.h).
//
// An accepted closure holds a direction alone where its leverage (the
// largest eigenvalue of its own block of G, at weight 1) exceeds
// kAloneLeverage: the rest of the map knows that direction a thousand
// times less well than the closure does, so nothing tests it.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "core/factor.h"
#include "core/factor_weights.h"
#include "core/values.h"

namespace hamal::robust {

// The expected number of false closures among the accepted that the
// `rejected` closures (with their c2, one each) predict, from their
// residuals at `estimate` and `weights`'s residual covariance; nothing when
// the back-end gives no residual covariance or a factor does not evaluate
// (the rule then stands without this evidence). Asks the covariance in
// blocks of kNearMissBlock closures, so memory stays small on large maps.
std::optional<double> expectedFalseAcceptances(FactorWeights& weights,
                                               const std::vector<const Factor*>& rejected,
                                               const std::vector<double>& c2,
                                               const Values& estimate);

// One closure's share of the estimate: k = r^T S^-1 r / c2 for a residual
// of `dim` rows; min(1, k^(-dim/2)).
double nearMissWeight(double k, int dim);

// How many of the `accepted` closures hold a direction of the map alone;
// nothing when the back-end gives no residual covariance. Only those the
// back-end holds at weight >= 0.5 count (GNC's are 0 or 1; PCM passes its
// accepted ones at 1): G is a closure's share of its own estimate only
// where the closure is in H.
std::optional<std::size_t> closuresAlone(FactorWeights& weights,
                                         const std::vector<const Factor*>& accepted);

// Both, for the share rule.
struct Refutation {
  double expected_false = 0;  // expectedFalseAcceptances
  std::size_t alone = 0;      // closuresAlone
};
std::optional<Refutation> refutation(FactorWeights& weights,
                                     const std::vector<const Factor*>& rejected,
                                     const std::vector<double>& c2,
                                     const std::vector<const Factor*>& accepted,
                                     const Values& estimate);

inline constexpr std::size_t kNearMissBlock = 64;
// Leverage 0.999: the closure's (I - G)^-1 amplifies its residual more than
// 1000-fold; GNC's tentative closures use the same bound.
inline constexpr double kAloneLeverage = 0.999;

}  // namespace hamal::robust
