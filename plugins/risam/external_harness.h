// What the harnesses here (hamal_risam_native, hamal_rpgo_native) share:
// hamal's poses and information matrices as GTSAM 4.2's, the protocol's
// anchor and guesses, a timed step, the command line and the end of a run,
// which writes what hamal_robust --estimate grades
// (apps/robust/external_solver.h) and the one-line summary. README.md here.
#pragma once

#include <gtsam/geometry/Pose2.h>
#include <gtsam/linear/NoiseModel.h>
#include <gtsam/nonlinear/PriorFactor.h>
#include <gtsam/nonlinear/Values.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "apps/bench/bench_writers.h"
#include "apps/bench/percentiles.h"
#include "apps/common/cli.h"
#include "apps/robust/external_solver.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/stopwatch.h"
#include "protocol/thesis_protocol.h"

namespace hamal::apps {

inline gtsam::Pose2 toGtsam(const Pose2& p) { return gtsam::Pose2(p.x, p.y, p.theta); }

// The file's information as GTSAM's noise model: g2o's and GTSAM's
// BetweenFactor<Pose2> share the residual (translation in the measurement's
// frame), so the matrix carries over unchanged.
inline gtsam::SharedNoiseModel noise(const Eigen::Matrix3d& information) {
  return gtsam::noiseModel::Gaussian::Information(information);
}

// The protocol's prior on pose 0, at the step's guess for it, with
// information diag(1e4, 1e4, 1e3) (docs/PROTOCOL.md).
inline gtsam::PriorFactor<gtsam::Pose2> anchorOf(const ThesisProtocol& protocol, const Step& step) {
  return gtsam::PriorFactor<gtsam::Pose2>(
      protocol.pose(0).index(), toGtsam(step.new_values.pose(protocol.pose(0))),
      gtsam::noiseModel::Diagonal::Precisions(gtsam::Vector3(1e4, 1e4, 1e3)));
}

// The step's new poses, keyed by their ids.
inline gtsam::Values guessesOf(const Step& step) {
  gtsam::Values guesses;
  for (const auto& [key, entry] : step.new_values)
    guesses.insert(key.index(), toGtsam(step.new_values.pose(key)));
  return guesses;
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

// Step i: `update` (the solver's update calls), then `estimate` (what the
// protocol reads next; the row's estimate phase), timed together, the
// estimate copied into out.estimate. GTSAM throws on an indeterminant
// system and the like: numerical trouble of the solver, a result of the
// run, not bad input; the row says so, out.failed is set and false
// returned.
inline bool timedStep(std::size_t i, const char* backend, HarnessOutcome& out,
                      const std::function<void()>& update,
                      const std::function<gtsam::Values()>& estimate) {
  StepRow row;
  row.step = i;
  row.backend = backend;
  row.kind = UpdateKind::kIncremental;
  const Stopwatch clock;
  try {
    update();
    const double updates = clock.seconds();
    const gtsam::Values now = estimate();
    row.work.seconds = clock.seconds();
    row.work.phases.estimate = row.work.seconds - updates;
    for (const auto& key_value : now) {
      const auto p = key_value.value.cast<gtsam::Pose2>();
      out.estimate.set(X(key_value.key), Pose2(p.x(), p.y(), p.theta()));
    }
  } catch (const std::exception& e) {
    row.work.seconds = clock.seconds();
    row.status = Status::kNumericalFailure;
    row.status_message = e.what();
    out.failed = true;
  }
  out.rows.push_back(row);
  return !out.failed;
}

// The verdicts in factor order, as hamal_robust --decisions reads them.
inline void sortByFactor(std::vector<ExternalDecision>& decisions) {
  std::sort(
      decisions.begin(), decisions.end(),
      [](const ExternalDecision& a, const ExternalDecision& b) { return a.factor < b.factor; });
}

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
    seconds.push_back(r.work.seconds);
    total += r.work.seconds;
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

// The flags every harness takes, by the names hamal_robust uses.
struct HarnessFlags {
  std::string data, format, output, decisions, rows;
};

// A harness's main after its command line is parsed: checks the flags,
// reads the graph, runs it and finishes the run (finishHarness).
inline int harnessMain(const std::vector<std::string>& positional, const HarnessFlags& flags,
                       const std::string& program, const std::string& solver,
                       const std::function<HarnessOutcome(const Graph&)>& run) {
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (flags.data.empty()) throw Error("--data is required (see --help)");
  checkOutputPaths({{"output", flags.output}, {"decisions", flags.decisions}, {"rows", flags.rows}},
                   {{"data", flags.data}});
  Registry registry;
  setUpRegistry(registry, {});
  const Graph graph = readGraph(flags.data, registry, parseFormat(flags.format));
  finishHarness(program, solver, flags.data, run(graph), graph, flags.rows, flags.output,
                flags.decisions);
  return 0;
}

}  // namespace hamal::apps
