// One FLAG run through a registered back-end, graded (flag_run.h).
#include "apps/flag/flag_run.h"

#include <time.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include "core/error.h"
#include "core/stopwatch.h"
#include "factors/max_mixture_factor.h"

namespace hamal::flag {
namespace {

double threadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace

RunErrors runErrors(const std::vector<Pose2>& estimate, const std::vector<Pose2>& truth) {
  RunErrors e;
  const std::size_t n = std::min(estimate.size(), truth.size());
  if (n == 0) return e;
  for (std::size_t i = 0; i < n; ++i) {
    const Point2 local = truth[i].transformTo(estimate[i].t());
    e.position += local.norm();
    e.longitudinal += std::abs(local.x());
    e.lateral += std::abs(local.y());
    e.heading += std::abs(wrapAngle(estimate[i].theta - truth[i].theta));
  }
  e.position /= n;
  e.longitudinal /= n;
  e.lateral /= n;
  e.heading /= n;
  e.last_position = (estimate[n - 1].t() - truth[n - 1].t()).norm();
  return e;
}

std::vector<LandmarkLabel> labelsOf(const FloorPlan& plan) {
  std::vector<LandmarkLabel> labels;
  for (const Corner& c : plan.corners) labels.push_back({c.id, c.label, {}});
  return labels;
}

std::string reasonCriterion(const std::string& reason) {
  std::string r = reason.substr(0, reason.find("; "));
  r = r.substr(0, r.find(" ("));
  // "=value" goes (not the '=' of ">="), and so does a word with a digit
  // after " at " (a key).
  std::string out;
  for (std::size_t i = 0; i < r.size();) {
    const bool assignment = r[i] == '=' && i + 1 < r.size() && r[i + 1] != ' ' &&
                            (i == 0 || std::string("<>!=").find(r[i - 1]) == std::string::npos);
    if (assignment) {
      while (i < r.size() && r[i] != ' ') ++i;
      continue;
    }
    if (r.compare(i, 4, " at ") == 0) {
      std::size_t end = i + 4;
      while (end < r.size() && r[end] != ' ' && r[end] != ':') ++end;
      const std::string word = r.substr(i + 4, end - i - 4);
      if (std::any_of(word.begin(), word.end(), [](unsigned char c) { return std::isdigit(c); })) {
        i = end;
        continue;
      }
    }
    out += r[i++];
  }
  return out;
}

UpdateSummary summarizeUpdates(const FlagRun& run) {
  UpdateSummary s;
  std::map<std::string, std::size_t> reasons;
  for (std::size_t i = 0; i < run.steps.rows.size(); ++i) {
    ++s.steps;
    const double cpu = i < run.steps.cpu_seconds.size() ? run.steps.cpu_seconds[i] : 0.0;
    const apps::StepRow& row = run.steps.rows[i];
    if (row.kind == UpdateKind::kBatch) {
      ++s.batch;
      ++reasons[reasonCriterion(row.reason)];
      s.batch_cpu_seconds.push_back(cpu);
    } else if (row.kind == UpdateKind::kIncremental) {
      ++s.incremental;
      if (row.reason.find("switched mode") != std::string::npos) ++s.mode_switches;
      s.incremental_cpu_seconds.push_back(cpu);
    }
  }
  s.batch_reasons.assign(reasons.begin(), reasons.end());
  std::stable_sort(s.batch_reasons.begin(), s.batch_reasons.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  return s;
}

FlagRun runFlag(const std::vector<LandmarkLabel>& labels, const Recording& recording,
                const FlagOptions& options, const Registry& registry) {
  options.validate();
  if (recording.steps.empty()) throw Error("FLAG: the recording has no poses");
  FlagRun result;
  const Pose2 start = recording.steps.front().truth;
  FlagLocalizer localizer(labels, recording, start, options);
  std::unique_ptr<Backend> backend = registry.makeBackend(options.backend);
  Pose2 dr = start;
  std::vector<std::shared_ptr<const MaxMixtureFactor>> mixtures;
  std::string non_finite;  // the first step whose estimate is not finite
  // A step's time is association + check + update: the clocks start before
  // the localizer makes the step.
  Stopwatch wall;
  double cpu_start = 0;
  apps::RunOptions run_options;
  run_options.score = false;  // graded by its errors against the truth
  run_options.hooks.before_step = [&](std::size_t) {
    wall.restart();
    cpu_start = threadCpuSeconds();
  };
  run_options.hooks.after_update = [&](std::size_t i, const Step& step, const UpdateResult&,
                                       const Backend& b) {
    const double cpu = threadCpuSeconds() - cpu_start;
    for (const FactorPtr& f : step.new_factors)
      if (auto m = std::dynamic_pointer_cast<const MaxMixtureFactor>(f)) mixtures.push_back(m);
    result.steps.seconds.push_back(wall.seconds());
    result.steps.cpu_seconds.push_back(cpu);
    const Pose2 est = b.estimate().pose(X(i));
    if (non_finite.empty() &&
        (!std::isfinite(est.x) || !std::isfinite(est.y) || !std::isfinite(est.theta)))
      non_finite = "step " + std::to_string(i) + ": non-finite estimate";
    if (i > 0) dr = dr.compose(recording.steps[i].odometry);
    result.truth.push_back(recording.steps[i].truth);
    result.online.push_back(est);
    result.dead_reckoning.push_back(dr);
    if (localizer.lost()) {
      if (result.lost.first < 0) result.lost.first = long(i);
      ++result.lost.steps;
    }
    const AssociationStats& so_far = localizer.stats();
    result.factors.so_far.push_back(so_far.accepted);
    result.factors.wrong_so_far.push_back(so_far.accepted - so_far.accepted_correct);
  };
  apps::RunResult run = apps::runSteps(localizer, *backend, options.backend, run_options);
  result.steps.rows = std::move(run.rows);
  const apps::RunOutcome outcome = apps::summarizeRows(result.steps.rows);
  result.ok = outcome.status.ok() && non_finite.empty();
  result.status = outcome.status.ok() ? non_finite : outcome.describe();
  result.stats = localizer.stats();
  result.final_estimate = backend->estimate();
  result.factors.mixtures = mixtures.size();
  for (const auto& m : mixtures)
    if (m->activeComponent(result.final_estimate) != 0) {
      ++result.factors.null_active;
      if (localizer.rightFactor(m.get())) ++result.factors.null_active_right;
    }
  result.flag = runErrors(result.online, result.truth);
  result.odometry = runErrors(result.dead_reckoning, result.truth);
  return result;
}

}  // namespace hamal::flag
