// The summary of a benchmark: see bench_summary.h.
#include "apps/bench/bench_summary.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "apps/bench/percentiles.h"
#include "core/error.h"

namespace hamal::apps {

Summary summarize(const std::string& dataset, const std::vector<RunResult>& runs,
                  const BatchOptimum* optimum) {
  if (runs.empty()) throw Error("summarize: no run");
  Summary s;
  s.dataset = dataset;
  s.backend = runs.front().backend;
  s.repeats = int(runs.size());
  const auto& first = runs.front().rows;
  s.steps = first.size();
  for (const auto& run : runs) {
    s.stopped_by_budget |= run.stopped_by_budget;
    s.steps = std::min(s.steps, run.rows.size());
  }

  std::vector<double> cumulative, update_only;
  for (const auto& run : runs) {
    if (run.rows.size() != s.steps && !s.stopped_by_budget)
      throw Error("summarize: runs of different lengths");
    double total = 0, estimate = 0;
    for (std::size_t i = 0; i < s.steps; ++i) {
      total += run.rows[i].work.seconds;
      estimate += run.rows[i].work.phases.estimate;
    }
    cumulative.push_back(total);
    update_only.push_back(total - estimate);
  }
  s.timing.cumulative_seconds = median(cumulative);
  s.timing.update_only_seconds = median(update_only);

  std::vector<double> per_step(s.steps);
  std::vector<double> samples(runs.size());
  for (std::size_t i = 0; i < s.steps; ++i) {
    for (std::size_t r = 0; r < runs.size(); ++r) samples[r] = runs[r].rows[i].work.seconds;
    per_step[i] = median(samples);
  }
  s.timing.p50 = percentile(per_step, 50);
  s.timing.p90 = percentile(per_step, 90);
  s.timing.p99 = percentile(per_step, 99);
  s.timing.max = per_step.empty() ? 0.0 : *std::max_element(per_step.begin(), per_step.end());
  s.timing.share_under_10ms = shareBelow(per_step, 0.010);
  s.timing.share_under_100ms = shareBelow(per_step, 0.100);

  // The first run's statuses over the steps every run ran (the one rule of
  // summarizeRows).
  const RunOutcome outcome =
      summarizeRows(std::vector<StepRow>(first.begin(), first.begin() + s.steps));
  s.outcome.batch_steps = outcome.batch_steps;
  s.outcome.non_ok_steps = outcome.non_ok_steps;
  s.outcome.first_failure = outcome.describe();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // With a budget the first run's chi2 may be at a later step than s.steps.
  s.accuracy.final_chi2 = first.size() == s.steps ? runs.front().final_chi2 : nan;
  s.outcome.failed =
      outcome.failed || (first.size() == s.steps && !std::isfinite(s.accuracy.final_chi2));
  s.accuracy.reference_usable = optimum && optimum->usable();
  s.accuracy.optimum_chi2 = s.accuracy.reference_usable ? optimum->chi2 : nan;
  s.accuracy.chi2_ratio = s.accuracy.reference_usable && !s.stopped_by_budget
                              ? s.accuracy.final_chi2 / optimum->chi2
                              : nan;
  s.accuracy.reference = optimum ? optimum->backend : "";
  s.accuracy.reference_note = optimum ? optimum->note : "";
  return s;
}

namespace {

std::string fixed(double v, int precision) {
  if (std::isnan(v)) return "-";
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << v;
  return os.str();
}

std::string milliseconds(double seconds) { return fixed(seconds * 1e3, 2); }

}  // namespace

void printSummaryTable(std::ostream& os, const std::vector<Summary>& summaries) {
  const std::vector<std::string> header = {
      "back-end", "steps",  "cumulative s", "p50 ms",     "p90 ms",   "p99 ms", "max ms",
      "<10ms",    "<100ms", "batch",        "final chi2", "chi2/opt", "not ok"};
  // The update-only column only when a back-end computes its estimate apart,
  // so tables of the built-in back-ends stay as they were.
  bool any_estimate = false;
  for (const auto& s : summaries)
    any_estimate |= s.timing.update_only_seconds != s.timing.cumulative_seconds;
  std::vector<std::vector<std::string>> lines = {header};
  if (any_estimate) lines.front().insert(lines.front().begin() + 3, "update-only s");
  for (const auto& s : summaries) {
    lines.push_back({s.backend, std::to_string(s.steps), fixed(s.timing.cumulative_seconds, 3),
                     milliseconds(s.timing.p50), milliseconds(s.timing.p90),
                     milliseconds(s.timing.p99), milliseconds(s.timing.max),
                     fixed(100 * s.timing.share_under_10ms, 1) + "%",
                     fixed(100 * s.timing.share_under_100ms, 1) + "%",
                     std::to_string(s.outcome.batch_steps), fixed(s.accuracy.final_chi2, 5),
                     !s.accuracy.reference.empty() && !s.accuracy.reference_usable
                         ? "n/a"
                         : fixed(s.accuracy.chi2_ratio, 6),
                     std::to_string(s.outcome.non_ok_steps)});
    if (any_estimate)
      lines.back().insert(lines.back().begin() + 3, fixed(s.timing.update_only_seconds, 3));
  }
  std::vector<std::size_t> width(lines.front().size(), 0);
  for (const auto& line : lines)
    for (std::size_t c = 0; c < line.size(); ++c) width[c] = std::max(width[c], line[c].size());
  for (const auto& line : lines) {
    for (std::size_t c = 0; c < line.size(); ++c) {
      // Back-end names left-aligned, figures right-aligned.
      if (c == 0)
        os << std::left << std::setw(int(width[c])) << line[c];
      else
        os << "  " << std::right << std::setw(int(width[c])) << line[c];
    }
    os << '\n';
  }
  os << std::left;
  if (!summaries.empty() && !summaries.front().accuracy.reference_note.empty())
    os << "chi2/opt: " << (summaries.front().accuracy.reference_usable ? "" : "n/a: ")
       << summaries.front().accuracy.reference_note << '\n';
  for (const auto& s : summaries)
    if (s.stopped_by_budget)
      os << s.backend << ": stopped by the time budget after " << s.steps
         << " steps (no chi2/opt: the optimum is the whole graph's)\n";
  for (const auto& s : summaries)
    if (!s.outcome.first_failure.empty())
      os << s.backend << ": " << s.outcome.non_ok_steps << " step(s) not ok, the worst at "
         << s.outcome.first_failure << '\n';
}

}  // namespace hamal::apps
