// The benchmark runner: the thesis protocol over a dataset (docs/PROTOCOL.md)
// through the step runner (apps/bench/step_runner.h), and the batch optimum
// the incremental results are compared with.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "apps/bench/step_runner.h"
#include "core/backend.h"
#include "core/graph.h"
#include "core/registry.h"
#include "core/step_source.h"
#include "core/values.h"
#include "protocol/thesis_protocol.h"

namespace hamal::apps {

// runSteps over the thesis protocol, its prior left out of chi2.
RunResult runThesisProtocol(const ThesisProtocol& protocol, Backend& backend,
                            const std::string& spec, const RunOptions& options, int run = 0);

// The dataset factors (not the prior) of steps 0..steps-1, in step order,
// and the odometry-composed guesses of their variables.
struct ProtocolPrefix {
  std::vector<FactorPtr> factors;
  Values initial;
};
ProtocolPrefix protocolPrefix(const ThesisProtocol& protocol, std::size_t steps);

// Where a batch solve starts: the odometry-composed values (docs/PROTOCOL.md,
// "Batch solves") or LAGO's linear estimate (protocol/lago_initialization.h), for
// worlds whose odometry drifts too far for Gauss-Newton.
enum class Initialization { kOdometry, kLago };
Initialization parseInitialization(const std::string& name);  // "odometry" | "lago"
const char* initializationName(Initialization init);

// Where a batch solve started: the initial values, made before its timed
// update.
struct BatchStart {
  Initialization from = Initialization::kOdometry;  // where the solve started
  double seconds = 0;  // computing the initial values (LAGO), not timed in the work
  double chi2 = 0;     // chi2 at the initial values
  std::string report;  // with LAGO: what it used and did not (describe(LagoResult))
};

// The batch optimum of the first `steps` steps (all of them for 0 or
// protocol.size()): one update of `reference_spec` on one step holding
// everything, from the initial values `init` names. chi2 over the dataset
// factors only; the initialisation is not part of the timed update.
struct BatchOptimum {
  std::string backend;
  std::size_t steps = 0;
  double chi2 = 0;
  UpdateWork work;  // the one timed update (phases: the back-end's split of its seconds)
  BatchStart init;
  Status status;
  Values estimate;
  // How the optimum was reached, or why there is none (solveReference).
  std::string note;
  // An optimum final chi2 may be divided by: the solve converged to a
  // finite chi2. A stopped solve is no optimum (see solveReference).
  bool usable() const;
};
// `solved`, when given, receives the back-end after its solve (to read
// what a wrapper decided, e.g. a robust model's weights).
BatchOptimum solveBatchOptimum(const Graph& graph, const ThesisProtocol& protocol,
                               std::size_t steps, const Registry& registry,
                               const std::string& reference_spec,
                               Initialization init = Initialization::kOdometry,
                               std::unique_ptr<Backend>* solved = nullptr);
// The one row of a --batch run: the solve as a batch update at the last
// step, with the back-end's split of its time.
StepRow batchStepRow(const BatchOptimum& batch);

// The reference of hamal_bench's chi2/opt: solveBatchOptimum from `init`;
// a solve from odometry that stops short of convergence (an iteration limit,
// a numerical failure) is retried from LAGO, which starts near the optimum
// on graphs whose odometry drifts. `note` says what happened; when neither
// solve converged, the result is not usable() and the ratio is n/a instead
// of a division by a point far from the optimum.
BatchOptimum solveReference(const Graph& graph, const ThesisProtocol& protocol, std::size_t steps,
                            const Registry& registry, const std::string& reference_spec,
                            Initialization init = Initialization::kOdometry);

}  // namespace hamal::apps
