// Backend: a solver that consumes Steps and keeps an estimate (README.md,
// "Design"). Every back-end sees the same factors through this
// interface, so an ablation changes one name and nothing else.
//
// update() tells what it did, as GTSAM's ISAM2Result does: batch or
// incremental and why, how much was relinearised and refactored, time per
// phase, and a Status. A numerical failure (a system that is not positive
// definite, a solver that cannot proceed) is a Status naming the variables
// involved; update() never aborts the process and never throws for it.
//
// Bad input is not a Status: every back-end passes the step to checkStep
// (core/step.h) before it records anything, so a bad step throws
// hamal::Error and leaves the back-end as it was, whichever back-end it is.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/key.h"
#include "core/step.h"
#include "core/values.h"

namespace hamal {

enum class UpdateKind { kNone, kIncremental, kBatch };
const char* toString(UpdateKind kind);

// ok: the answer converged within the back-end's stated tolerances and
// nothing the back-end can check casts doubt on it. kNotConverged: it
// stopped on an iteration budget, or ended above where it started.
// kUncertain: a robust back-end converged but its answer is in doubt (a
// cheaper alternative it checked, decisions that flip back and forth, most
// loop closures rejected); `message` names the rule that fired
// (backends/robust/README.md, "When the answer is in doubt").
struct Status {
  enum Code { kOk, kNumericalFailure, kNotConverged, kUncertain };
  Code code = kOk;
  std::string message;    // empty when ok
  std::vector<Key> keys;  // the variables involved, when known

  bool ok() const { return code == kOk; }
  static Status numericalFailure(std::string message, std::vector<Key> keys = {});
  static Status uncertain(std::string message);
};
const char* toString(Status::Code code);

// Seconds spent in each phase of one update (thesis fig. 3.8 breaks the
// cost down the same way). Phases a back-end does not have stay 0.
//
// `estimate` is the part of the step spent making the estimate estimate()
// returns, for a back-end whose update leaves it to be computed apart (GTSAM's
// iSAM2: update() then calculateEstimate()). The protocol needs that estimate
// every step, so it is part of the step's time; seconds minus `estimate` is
// the update alone, which GTSAM's own figures report.
struct PhaseTimes {
  double linearize = 0, order = 0, factor = 0, solve = 0, other = 0, estimate = 0;
  double total() const { return linearize + order + factor + solve + other + estimate; }
};

struct UpdateResult {
  UpdateKind kind = UpdateKind::kNone;
  std::string reason;  // why this kind ("periodic", "|L| >= NL_T", ...)
  Status status;
  int iterations = 0;         // nonlinear iterations (Gauss-Newton / LM)
  std::size_t variables = 0;  // variables in the estimate after the update
  std::size_t variables_relinearized = 0;
  std::size_t columns_recomputed = 0;  // scalar columns of R refactored
  std::size_t columns_total = 0;       // scalar columns of R
  PhaseTimes time;
};

class Backend {
 public:
  virtual ~Backend() = default;
  // Adds the step's variables and factors, then updates the estimate.
  virtual UpdateResult update(const Step& step) = 0;
  // The current estimate of every variable added so far.
  virtual const Values& estimate() const = 0;
};

}  // namespace hamal
