// ClosingVerdict: a capability a Backend may offer besides update(): its
// verdict on the answer as it stands when a run is over. A robust model's
// doubt rules (backends/robust/README.md, "When the answer is in doubt")
// re-solve alternatives only when the loop closures have grown by a set
// factor, so the status of a run's last update can be a verdict on the map
// of some steps before, with every closure that came since unchecked. A
// tool that knows the run is over calls closingVerdict() once after the
// last update, and reads the estimate after it; a status that is not ok
// replaces the last update's ok, and after an uncertain update, where the
// back-end judgesUncertainAnswers(), any status replaces it
// (apps/bench/step_runner.h does this for every tool).
//
// A back-end that offers it derives from both Backend and ClosingVerdict;
// a caller finds it with dynamic_cast.
#pragma once

#include "core/backend.h"

namespace hamal {

class ClosingVerdict {
 public:
  virtual ~ClosingVerdict() = default;
  // Runs the checks due at the end on the current estimate: ok, or a Status
  // naming what casts doubt on the answer (kUncertain). May adopt a better
  // answer when the model's mode says so (GNC's gnc_closing=adopt), so a
  // caller reads the estimate after it; the status is then the verdict on
  // the adopted answer.
  virtual Status closingVerdict() = 0;
  // Whether closingVerdict() also judges an answer whose last update was
  // kUncertain, its status then replacing that one whatever it is (a
  // robust model that can find and adopt a better answer at the end: GNC's
  // gnc_group=on). False (the default): it is asked only after an ok
  // update, and an ok verdict leaves the update's status.
  virtual bool judgesUncertainAnswers() const { return false; }
};

}  // namespace hamal
