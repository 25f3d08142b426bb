// VariablePrediction: the capability of a factor that can guess one of its
// variables from the others (odometry composes, a landmark observation
// projects), by which the thesis protocol (protocol/thesis_protocol.h,
// thesis sec. 3.5.1) and LAGO's landmark pass initialise each new variable.
// A factor kind opts in by deriving from Factor and VariablePrediction; the
// protocol cannot initialise a variable that only other factors touch.
#pragma once

#include "core/factor.h"
#include "core/key.h"
#include "core/values.h"

namespace hamal {

class VariablePrediction {
 public:
  virtual ~VariablePrediction() = default;

  // A guess for variable `unknown` (one of the factor's keys) from the other
  // keys' values in `known`; false when this factor cannot tell (`unknown`
  // is not one it predicts, or a key it needs is not known).
  virtual bool predict(Key unknown, const Values& known, Values::Entry* guess) const = 0;
};

// `factor`'s guess for `unknown` as VariablePrediction::predict; false for a
// factor that predicts nothing.
inline bool predictVariable(const Factor& factor, Key unknown, const Values& known,
                            Values::Entry* guess) {
  const auto* p = dynamic_cast<const VariablePrediction*>(&factor);
  return p && p->predict(unknown, known, guess);
}

}  // namespace hamal
