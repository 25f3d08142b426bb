// The bad-step table of the conformance suite (core/step.h, core/backend.h:
// the one input contract of every back-end). Each bad step must throw
// hamal::Error whose message contains `says`, and leave the back-end as it
// was: the next good step then gives what it gives on a back-end that never
// saw the bad one. Each bad step carries good parts (a new variable, a good
// factor) before the bad one, so that a back-end recording as it checks
// would show.
#pragma once

#include <functional>
#include <vector>

#include "core/step.h"

namespace hamal::testing {

struct BadStep {
  const char* name;
  const char* says;  // a part of the message
  std::function<Step()> make;
};

// Two good steps (x0..x2, a prior and odometry) to give before a bad one,
// and a good one (x3 and a loop closure) to give after it.
Step firstGoodStep();
Step secondGoodStep();
Step goodStepAfter();

// A variable added twice, a null factor, a factor on an unknown variable, a
// pose factor on a point, a fixed key that names no variable, a factor that
// names one variable twice, a guess that is not finite.
const std::vector<BadStep>& badSteps();

}  // namespace hamal::testing
