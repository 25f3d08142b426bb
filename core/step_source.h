// StepSource: where the Steps a back-end consumes come from (thesis
// Alg. 3.1, line 2). The thesis protocol over a dataset is one source; a
// simulated robot (FLAG's, MOSS's) is another. The bench runner and the
// back-ends do not care which.
//
// A source may make step i from the back-end's current estimate (the thesis
// protocol composes odometry from it, a localizer associates measurements
// through it), so steps are asked for in order, one back-end update between
// two calls: step(0, estimate), update, step(1, estimate), ...
#pragma once

#include <cstddef>
#include <string>

#include "core/step.h"
#include "core/values.h"

namespace hamal {

class StepSource {
 public:
  virtual ~StepSource() = default;
  // Number of steps.
  virtual std::size_t size() const = 0;
  // Step i, made from `estimate`, which holds every variable of the steps
  // before i as the back-end estimated them.
  virtual Step step(std::size_t i, const Values& estimate) = 0;
};

}  // namespace hamal
