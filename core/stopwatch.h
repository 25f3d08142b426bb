// Stopwatch: the steady clock every figure is timed with (docs/PROTOCOL.md,
// "The thesis protocol": only update calls are timed, with a steady clock).
#pragma once

#include <chrono>

namespace hamal {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void restart() { start_ = Clock::now(); }
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  // Seconds since the last lap (or start), and starts a new lap.
  double lap() {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return s;
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

}  // namespace hamal
