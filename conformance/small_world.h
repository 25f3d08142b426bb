// The conformance suite's worlds (conformance/backend_conformance.h): a
// square driven twice around, twelve poses a lap, with a loop closure from
// each pose of the second lap to its twin of the first and four landmarks
// seen every other pose; odometry carries a deterministic noise, so the
// odometry-composed start is off the optimum and every free variable moves.
// Small enough that the thesis protocol (thesis sec. 3.5.1) runs through it
// in milliseconds on any back-end, rich enough to have loops, landmarks and
// both variable types.
#pragma once

#include <vector>

#include "core/graph.h"
#include "core/step.h"

namespace hamal::testing {

// 24 poses x0..x23, landmarks l0..l3; no prior and no fixed variable (the
// thesis protocol adds the prior; a test may set Graph::fixed).
Graph smallWorld();

// A straight chain of `n` poses 1 m apart, guessed a little off, with a
// strong prior on x0 and unit-information odometry, as one step, then
// `extra`: the ground the bad-number tests put one bad factor on.
Step chainStep(int n, std::vector<FactorPtr> extra = {});

}  // namespace hamal::testing
