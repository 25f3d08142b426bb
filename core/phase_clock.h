// PhaseClock: times one update phase by phase into its PhaseTimes
// (core/backend.h; thesis fig. 3.8 breaks the cost down the same way), on
// the steady clock every figure is timed with (core/stopwatch.h).
//
//   PhaseClock clock;
//   ... linearise ...   clock.lap(&result.time.linearize);
//   ... factorise ...   clock.lap(&result.time.factor);
//   clock.finish(&result.time);   // before each return
//
// finish() puts whatever no phase counted into `other`, so the phases always
// sum to the update's wall time, whichever path returned.
#pragma once

#include <algorithm>

#include "core/backend.h"
#include "core/stopwatch.h"

namespace hamal {

class PhaseClock {
 public:
  // Adds the seconds since the last lap (or the start) to `phase`.
  void lap(double* phase) { *phase += lap_.lap(); }
  // Seconds since the start.
  double seconds() const { return total_.seconds(); }
  // Adds the time since the start that `times` does not count yet to other.
  void finish(PhaseTimes* times) const {
    times->other += std::max(0.0, total_.seconds() - times->total());
  }

 private:
  Stopwatch total_, lap_;
};

}  // namespace hamal
