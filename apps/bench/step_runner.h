// The step runner: one back-end fed by one StepSource, one update per step
// (thesis sec. 3.5.1, Alg. 3.1's outer loop). hamal_bench, hamal_solve and
// hamal_robust run the thesis protocol through it; FLAG (sec. 4.4), its
// Victoria Park reference and MOSS' localizer (sec. 5.3.2) run their
// simulated robots through it, with hooks for what they time or record
// beside the update.
//
// Step i is made from the back-end's current estimate
// (source.step(i, backend.estimate())) and handed to backend.update(step);
// only that update call is timed (core/stopwatch.h). chi2 is computed
// outside the timed region by the one evaluator (core/metrics.h), over the
// measurement factors added so far: a factor the source adds only to fix the
// gauge (the protocol's prior) is not one.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/step_source.h"
#include "core/values.h"

namespace hamal::apps {

// What one update cost: its time and the work the back-end says it did.
struct UpdateWork {
  double seconds = 0;  // wall time of update() alone
  int iterations = 0;
  std::size_t columns_recomputed = 0;
  std::size_t variables_relinearized = 0;
  PhaseTimes phases;  // the back-end's own split of its time (UpdateResult::time)
};

// One update, as the per-step files hold it.
struct StepRow {
  int run = 0;  // repetition (0-based) when a back-end is run several times
  std::size_t step = 0;
  std::string backend;  // the spec as given ("ceres:max_iterations=50")
  UpdateKind kind = UpdateKind::kNone;
  std::string reason;
  Status::Code status = Status::kOk;
  std::string status_message;
  UpdateWork work;
  std::optional<double> chi2;  // dataset factors so far; empty when not computed at this step
};

// What a caller adds to the loop without writing it again. Both are
// optional; neither is inside the timed update.
struct StepHooks {
  // Before step i is made: a caller that times the making of the step too
  // (FLAG's association) starts its clocks here.
  std::function<void(std::size_t i)> before_step;
  // After step i's update, before its chi2: the step, what the back-end
  // said, and the back-end (its estimate now includes step i).
  std::function<void(std::size_t i, const Step& step, const UpdateResult& result,
                     const Backend& backend)>
      after_update;
};

struct RunOptions {
  std::size_t max_steps = 0;   // 0: every step of the source
  std::size_t chi2_every = 1;  // chi2 at every k-th step and the last one; 0: the last one only
  // No chi2 at all (a localizer graded by its own errors, not by chi2).
  bool score = true;
  // Seconds of update calls after which a run stops (0: none): the step at
  // which the cumulative time reaches it is the run's last. For comparisons
  // where one back-end would take hours: its curve up to the budget, against
  // the others' whole runs.
  double time_budget = 0;
  // Factors the source adds that are not measurements (a gauge prior): left
  // out of chi2. runThesisProtocol puts the protocol's prior here.
  std::vector<const Factor*> not_scored;
  StepHooks hooks;
};

struct RunResult {
  std::string backend;
  std::vector<StepRow> rows;
  Values estimate;                  // after the last step
  double final_chi2 = 0;            // dataset factors of the steps run (0 without score)
  std::size_t dataset_factors = 0;  // how many
  bool stopped_by_budget = false;   // RunOptions::time_budget ended it before the last step
};

// Runs `backend` over the first options.max_steps steps of `source`, one
// update per step. `spec` labels the rows; `run` numbers repetitions. After
// a last update that is ok, a back-end offering ClosingVerdict
// (core/closing_verdict.h) gives its verdict, which may adopt a better
// answer: the last chi2 and the estimate are read after it.
RunResult runSteps(StepSource& source, Backend& backend, const std::string& spec,
                   const RunOptions& options, int run = 0);

// chi2 of `factors` at `values`, or NaN when `values` lacks a variable: a
// back-end that failed may have none, which a summary reports instead of an
// exception that ends the benchmark.
double chi2OrNaN(const std::vector<FactorPtr>& factors, const Values& values);

// The one account of a run's statuses, which every tool prints.
//
// A step that did not converge (an iteration limit) leaves a finite estimate
// the next step continues from; a numerical failure may leave none. So a
// numerical failure outranks a step that did not converge: the run's status
// is the worst code of its steps with the message of the first step of that
// code; every non-ok step counts in non_ok_steps. The run
// ended in a failure (`failed`) when its last step is a numerical failure:
// a last step that did not converge still leaves an estimate to grade.
struct RunOutcome {
  std::size_t steps = 0;
  std::size_t batch_steps = 0;
  std::size_t non_ok_steps = 0;
  double seconds = 0;  // the updates' wall time
  int iterations = 0;
  // The worst code (numerical_failure > not_converged > uncertain), and the
  // message of its first step; uncertain counts only on the last step.
  Status status;
  std::size_t status_step = 0;  // that step (when status is not ok)
  bool failed = false;
  // "step N: code: message" (": message" only when there is one); empty when ok.
  std::string describe() const;
};
RunOutcome summarizeRows(const std::vector<StepRow>& rows);

}  // namespace hamal::apps
