// The conformance suite's world (conformance/backend_conformance.h): a
// square driven twice around, twelve poses a lap, with a loop closure from
// each pose of the second lap to its twin of the first and four landmarks
// seen every other pose; odometry carries a deterministic noise, so the
// odometry-composed start is off the optimum and every free variable moves.
// Small enough that the thesis protocol (thesis sec. 3.5.1) runs through it
// in milliseconds on any back-end, rich enough to have loops, landmarks and
// both variable types.
#pragma once

#include "core/graph.h"

namespace hamal::testing {

// 24 poses x0..x23, landmarks l0..l3; no prior and no fixed variable (the
// thesis protocol adds the prior; a test may set Graph::fixed).
Graph smallWorld();

}  // namespace hamal::testing
