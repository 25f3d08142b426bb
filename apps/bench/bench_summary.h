// The summary of a benchmark: the figures docs/PROTOCOL.md asks for, per
// back-end (cumulative time; per-step p50 / p90 / p99 / max; share of steps
// under 10 ms and 100 ms; batch steps; final chi2 and its ratio to the batch
// optimum; failures), and the comparison table hamal_bench prints.
#pragma once

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "apps/bench/bench_runner.h"

namespace hamal::apps {

// Times: with several repeats, the median of the runs' cumulative times,
// and percentiles over each step's median time.
struct SummaryTiming {
  double cumulative_seconds = 0;
  // The same without PhaseTimes::estimate (the update calls alone, for a
  // back-end that computes its estimate apart; = cumulative_seconds otherwise).
  double update_only_seconds = 0;
  double p50 = 0, p90 = 0, p99 = 0, max = 0;           // seconds per step
  double share_under_10ms = 0, share_under_100ms = 0;  // 0..1
};

// The steps' kinds and statuses, from the first run.
struct SummaryOutcome {
  std::size_t batch_steps = 0;
  std::size_t non_ok_steps = 0;
  // RunOutcome::describe(): the worst status, at its first step
  // ("step 12: numerical_failure: ..."), or empty.
  std::string first_failure;
  // The run ended in a failure: RunOutcome::failed (its last step was a
  // numerical failure), or its final chi2 is not finite.
  bool failed = false;
};

// The final chi2 (from the first run, where chi2 is computed) against the
// batch optimum of a reference back-end.
struct SummaryAccuracy {
  double final_chi2 = 0;
  double optimum_chi2 = 0;  // NaN when no reference was solved
  double chi2_ratio = 0;    // final / optimum (1 = the batch optimum)
  std::string reference;    // the back-end that gave the optimum
  // Set when a reference was solved: how (a LAGO retry), or why it gives no
  // optimum (then optimum_chi2 and chi2_ratio are NaN and the table says n/a).
  std::string reference_note;
  bool reference_usable = false;
};

struct Summary {
  std::string dataset;
  std::string backend;
  std::size_t steps = 0;
  int repeats = 0;
  SummaryTiming timing;
  SummaryOutcome outcome;
  SummaryAccuracy accuracy;
  // A run stopped by RunOptions::time_budget: steps is the shortest run's,
  // times are over those steps, and there is no chi2/opt (the optimum is
  // the whole graph's).
  bool stopped_by_budget = false;
};

// `runs` are repeats of one back-end on one dataset (at least one).
// `optimum` may be null; one that is not usable() gives no ratio.
Summary summarize(const std::string& dataset, const std::vector<RunResult>& runs,
                  const BatchOptimum* optimum);

// The comparison table, one line per back-end.
void printSummaryTable(std::ostream& os, const std::vector<Summary>& summaries);

}  // namespace hamal::apps
