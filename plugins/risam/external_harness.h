// What the harnesses here (hamal_risam_native, hamal_rpgo_native) share:
// hamal's poses and information matrices as GTSAM 4.2's, and the end of a
// run, which writes what hamal_robust --estimate grades
// (apps/robust/external_solver.h) and the one-line summary. README.md here.
#pragma once

#include <gtsam/geometry/Pose2.h>
#include <gtsam/linear/NoiseModel.h>

#include <cstdio>
#include <string>
#include <vector>

#include "apps/bench/bench_writers.h"
#include "apps/bench/percentiles.h"
#include "apps/robust/external_solver.h"
#include "core/error.h"
#include "core/graph_io.h"

namespace hamal::apps {

inline gtsam::Pose2 toGtsam(const Pose2& p) { return gtsam::Pose2(p.x, p.y, p.theta); }

// The file's information as GTSAM's noise model: g2o's and GTSAM's
// BetweenFactor<Pose2> share the residual (translation in the measurement's
// frame), so the matrix carries over unchanged.
inline gtsam::SharedNoiseModel noise(const Eigen::Matrix3d& information) {
  return gtsam::noiseModel::Gaussian::Information(information);
}

// A run under the thesis protocol: one row per step, the last estimate, the
// solver's verdict on every loop closure (in factor order); `failed` when a
// step ended it (its row says why).
struct HarnessOutcome {
  std::vector<StepRow> rows;
  Values estimate;
  std::vector<ExternalDecision> decisions;
  bool failed = false;
};

// Writes the files named (empty: not written) and prints the summary line.
// A run that did not end writes nothing and throws naming the step: there
// is no estimate to grade.
inline void finishHarness(const std::string& program, const std::string& solver,
                          const std::string& data, const HarnessOutcome& out, const Graph& graph,
                          const std::string& rows_path, const std::string& output_path,
                          const std::string& decisions_path) {
  if (out.failed) {
    const StepRow& last = out.rows.back();
    throw Error(data + ": " + solver + " failed at step " + std::to_string(last.step) + " (" +
                toString(last.status) + "): " + last.status_message);
  }
  std::vector<double> seconds;
  double total = 0;
  for (const StepRow& r : out.rows) {
    seconds.push_back(r.seconds);
    total += r.seconds;
  }
  if (!rows_path.empty()) writeRowsFile(rows_path, out.rows);
  if (!output_path.empty()) writeG2o(output_path, out.estimate, graph.factors);
  if (!decisions_path.empty()) writeExternalDecisions(decisions_path, program, data, out.decisions);
  std::size_t rejected = 0;
  for (const auto& d : out.decisions) rejected += d.rejected;
  std::printf(
      "%s: %s: %zu steps, %.3f s (step p50 %.2f ms, p99 %.2f ms), %zu of %zu "
      "loop closures rejected\n",
      program.c_str(), data.c_str(), out.rows.size(), total, 1e3 * percentile(seconds, 50),
      1e3 * percentile(seconds, 99), rejected, out.decisions.size());
}

}  // namespace hamal::apps
