// GaugeFreedom: whether a pose graph's optimum is unique up to nothing or
// only up to a rigid motion of a part of it. Relative measurements (between,
// range-bearing, pose-point factors) leave each connected part of the graph
// free to move as a whole; a prior (any factor on one variable) or a fixed
// variable (Step::fixed) anchors the part it touches. A part that nothing
// anchors has no unique least-squares solution: its normal equations are
// singular, and every back-end says so in one way, a numerical-failure
// Status naming a variable of that part, with the estimate left as it was
// (GTSAM refuses the same graph with IndeterminantLinearSystemException).
//
// The test is structural and cheap (one union-find pass over the factors),
// so a back-end can run it before it solves, or when its factorisation meets
// a singular pivot to say why. It finds every part with no anchor at all;
// a part anchored in some directions only (a landmark position prior with
// nothing fixing rotation) is left to the factorisation's pivot test.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/key.h"

namespace hamal {

// A variable of the first connected part (in the order of `variables`) that
// neither holds a fixed variable nor is touched by a one-variable factor;
// nothing when every part is anchored. A variable no factor touches is a
// part of its own, anchored only when fixed.
std::optional<Key> unanchoredVariable(const std::vector<Key>& variables,
                                      const std::vector<FactorPtr>& factors,
                                      const std::vector<Key>& fixed);

// ok, or the numerical failure naming that variable; `backend` prefixes the
// message.
Status gaugeFreedomStatus(const std::string& backend, const std::vector<Key>& variables,
                          const std::vector<FactorPtr>& factors, const std::vector<Key>& fixed);

}  // namespace hamal
