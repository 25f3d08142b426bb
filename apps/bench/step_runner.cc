// The step runner: see step_runner.h.
#include "apps/bench/step_runner.h"

#include <algorithm>
#include <limits>

#include "core/closing_verdict.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/stopwatch.h"

namespace hamal::apps {

double chi2OrNaN(const std::vector<FactorPtr>& factors, const Values& values) {
  try {
    return chi2(factors, values);
  } catch (const Error&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

namespace {

int severity(Status::Code code) {
  switch (code) {
    case Status::kOk:
      return 0;
    case Status::kUncertain:
      return 1;
    case Status::kNotConverged:
      return 2;
    case Status::kNumericalFailure:
      return 3;
  }
  return 3;
}

}  // namespace

RunResult runSteps(StepSource& source, Backend& backend, const std::string& spec,
                   const RunOptions& options, int run) {
  RunResult out;
  out.backend = spec;
  const std::size_t steps =
      options.max_steps ? std::min(options.max_steps, source.size()) : source.size();
  out.rows.reserve(steps);
  const auto& skip = options.not_scored;
  const StepHooks& hooks = options.hooks;
  std::vector<FactorPtr> dataset;
  double cumulative = 0;
  for (std::size_t i = 0; i < steps; ++i) {
    if (hooks.before_step) hooks.before_step(i);
    const Step step = source.step(i, backend.estimate());
    if (options.score)
      for (const auto& f : step.new_factors)
        if (std::find(skip.begin(), skip.end(), f.get()) == skip.end()) dataset.push_back(f);

    Stopwatch watch;
    const UpdateResult result = backend.update(step);
    const double seconds = watch.seconds();
    if (hooks.after_update) hooks.after_update(i, step, result, backend);

    StepRow row;
    row.run = run;
    row.step = i;
    row.backend = spec;
    row.kind = result.kind;
    row.reason = result.reason;
    row.status = result.status.code;
    row.status_message = result.status.message;
    row.work.seconds = seconds;
    row.work.iterations = result.iterations;
    row.work.columns_recomputed = result.columns_recomputed;
    row.work.variables_relinearized = result.variables_relinearized;
    row.work.phases = result.time;
    cumulative += seconds;
    const bool over_budget = options.time_budget > 0 && cumulative >= options.time_budget;
    const bool last = i + 1 == steps || over_budget;
    // The closing verdict before the last chi2: it may adopt a better answer.
    auto* verdict = last ? dynamic_cast<ClosingVerdict*>(&backend) : nullptr;
    const bool rejudged =
        verdict && row.status == Status::kUncertain && verdict->judgesUncertainAnswers();
    if (verdict && (row.status == Status::kOk || rejudged)) {
      Stopwatch closing;
      const Status s = verdict->closingVerdict();
      row.work.seconds += closing.seconds();
      if (!s.ok() || rejudged) {
        row.status = s.code;
        row.status_message = s.message;
      }
    }
    if (options.score && (last || (options.chi2_every > 0 && i % options.chi2_every == 0)))
      row.chi2 = chi2OrNaN(dataset, backend.estimate());
    out.rows.push_back(std::move(row));
    if (last) {
      out.stopped_by_budget = i + 1 < steps;
      break;
    }
  }
  out.estimate = backend.estimate();
  out.final_chi2 = out.rows.empty() || !out.rows.back().chi2 ? 0.0 : *out.rows.back().chi2;
  out.dataset_factors = dataset.size();
  return out;
}

RunOutcome summarizeRows(const std::vector<StepRow>& rows) {
  RunOutcome o;
  o.steps = rows.size();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const StepRow& row = rows[i];
    o.seconds += row.work.seconds;
    o.iterations += row.work.iterations;
    if (row.kind == UpdateKind::kBatch) ++o.batch_steps;
    // Doubt is about the answer: an earlier step's doubt that a later
    // update resolved leaves nothing in doubt.
    if (row.status == Status::kOk || (row.status == Status::kUncertain && i + 1 < rows.size()))
      continue;
    ++o.non_ok_steps;
    if (severity(row.status) > severity(o.status.code)) {
      o.status.code = row.status;
      o.status.message = row.status_message;
      o.status_step = row.step;
    }
  }
  o.failed = !rows.empty() && rows.back().status == Status::kNumericalFailure;
  return o;
}

std::string RunOutcome::describe() const {
  if (status.ok()) return "";
  return "step " + std::to_string(status_step) + ": " + toString(status.code) +
         (status.message.empty() ? "" : ": " + status.message);
}

}  // namespace hamal::apps
