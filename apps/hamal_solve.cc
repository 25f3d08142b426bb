// hamal_solve: solves one graph file with one back-end, picked by name
// (README.md, "Design"): a batch solve from the odometry-composed initial
// values (docs/PROTOCOL.md, "Batch solves") or, with --incremental, one
// update per pose under the thesis protocol (thesis sec. 3.5.1). Prints chi2
// before and after (core/metrics.h, dataset factors only), iterations, the
// time spent in update calls, and the back-end's status; writes the result as
// g2o. A back-end spec may carry a loop-closure model (robust=gnc-tls, ...,
// apps/robust/README.md): then the loop closures it rejected are counted.
#include <gflags/gflags.h>

#include <algorithm>
#include <iomanip>
#include <iostream>

#include "apps/bench/bench_runner.h"
#include "apps/common/cli.h"
#include "apps/robust/robust_evaluation.h"
#include "apps/robust/robust_loop_closures.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/stopwatch.h"
#include "factors/between_factor.h"
#include "protocol/lago_initialization.h"
#include "protocol/thesis_protocol.h"

DEFINE_string(data, "", "the graph file to solve (or give it as the only positional argument)");
HAMAL_FLAG_ALIAS(input, data);
DEFINE_string(format, "auto", "input format: auto | g2o | toro | gtsam (core/graph_io.h)");
DEFINE_string(backend, "cholesky",
              "back-end spec: a registered name with options, e.g. \"cholesky\" or "
              "\"ceres:max_iterations=50\" (see --list-backends)");
DEFINE_bool(incremental, false,
            "run the thesis protocol (one update per pose) instead of one batch solve");
DEFINE_string(init, "odometry",
              "batch mode's initial values: odometry (composed, docs/PROTOCOL.md) or lago (linear "
              "orientation-then-position estimate, protocol/lago_initialization.h)");
DEFINE_string(output, "", "write the estimate and the graph's factors to this g2o file");
DEFINE_string(
    residual, "thesis",
    "residual of the between factors: thesis (the chi2 of docs/PROTOCOL.md) | measurement "
    "(g2o's and GTSAM's, translation error in the measurement frame)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "solves a pose graph with one back-end.\n\n"
    "  hamal_solve --data M3500.toro --backend cholesky --output result.g2o\n"
    "  hamal_solve M3500.toro --backend \"ceres:max_iterations=50\" --incremental\n"
    "  hamal_solve M3500.toro --backend cholesky:robust=gnc-tls     # loop closures may be "
    "false\n\n"
    "Prints chi2 before (odometry-composed initial values) and after, over the file's\n"
    "factors (no prior), the iterations, the time of the update calls, and the status.\n"
    "Exit status: 0 ok, 1 error (bad input or options), 2 the back-end reported a\n"
    "numerical failure or did not converge, 3 it converged but its answer is in doubt\n"
    "(status uncertain: a robust back-end's doubt rule fired).";

int solve(const std::vector<std::string>& plugins, const std::vector<std::string>& positional) {
  Registry base;
  setUpRegistry(base, plugins);
  const Registry registry = robustRegistry(base);
  if (printListings(registry)) return 0;
  std::string input = FLAGS_data;
  if (positional.size() + (FLAGS_data.empty() ? 0 : 1) > 1) {
    std::string inputs = FLAGS_data.empty() ? "" : "--data " + FLAGS_data;
    for (const std::string& p : positional) inputs += (inputs.empty() ? "'" : ", '") + p + "'";
    throw Error("more than one input (" + inputs + "): hamal_solve solves one graph");
  }
  if (input.empty() && positional.size() == 1) input = positional[0];
  if (input.empty()) throw Error("no input file: give --data FILE (see --help)");
  const BetweenResidual residual = parseResidual(FLAGS_residual);
  // Options first: a misspelt back-end is reported before a long read.
  const BackendSpec spec = BackendSpec::parse(FLAGS_backend);
  const Options options = registry.resolveOptions(spec);
  const RobustOptions robust = robustOptionsFrom(options);
  // Made now, so that an option's bad value (delta_t=abc) is reported
  // before the read, and every output path checked before the solve.
  std::unique_ptr<Backend> backend = registry.makeBackend(spec);
  const Format format = parseFormat(FLAGS_format);
  const Initialization init = parseInitialization(FLAGS_init);
  if (FLAGS_incremental && init != Initialization::kOdometry)
    throw Error("--init applies to batch mode: the thesis protocol initialises each pose itself");
  checkOutputPaths({{"output", FLAGS_output}}, {{FLAGS_data.empty() ? "" : "data", input}});

  Graph graph = readGraph(input, base, format);
  setBetweenResidual(graph, residual);
  // The back-end sees the model's factors; chi2 and --output are over the
  // file's own.
  Graph model = graph;
  if (robust.method != RobustMethod::kLeastSquares) {
    if (std::none_of(graph.factors.begin(), graph.factors.end(),
                     [](const FactorPtr& f) { return isLoopClosure(*f); }))
      throw Error(input +
                  ": no loop closure (a factor between poses whose ids differ by more than one): "
                  "robust=" +
                  robustMethodName(robust.method) + " has nothing to decide");
    model.factors = applyRobustMethod(graph.factors, robust);
  }
  std::size_t poses = 0, others = 0;
  for (Key k : graph.keys()) (k.kind() == kPoseKind ? poses : others)++;
  std::cout << "input:       " << input << ": " << poses << " poses, " << others
            << " other variables, " << graph.factors.size() << " factors (format " << FLAGS_format
            << ", " << betweenResidualName(residual) << " residual)\n";
  std::cout << "back-end:    " << spec.name << (options.values().empty() ? "" : ":" + options.str())
            << "\n";

  const ThesisProtocol protocol(model);
  const double before = chi2(graph.factors, protocol.initialValues());

  double seconds = 0;
  int iterations = 0;
  std::size_t failures = 0;
  std::string first_failure;  // the worst status (summarizeRows)
  Status::Code worst = Status::kOk;
  if (FLAGS_incremental) {
    std::cout << "mode:        incremental (thesis protocol, " << protocol.size() << " steps)\n";
    RunOptions run_options;
    run_options.chi2_every = 0;  // only the final chi2, outside the timed updates
    const RunOutcome outcome =
        summarizeRows(runThesisProtocol(protocol, *backend, spec.str(), run_options).rows);
    seconds = outcome.seconds;
    iterations = outcome.iterations;
    failures = outcome.non_ok_steps;
    first_failure = outcome.describe();
    worst = outcome.status.code;
  } else {
    Step batch = protocol.batch();
    if (init == Initialization::kLago) {
      Stopwatch init_watch;
      const Values odometry = batch.new_values;
      LagoResult lago = lagoInitialization(batch.new_factors, batch.new_values);
      const double lago_seconds = init_watch.seconds();
      batch.new_values = std::move(lago.values);
      // A fixed variable is held where the file puts it, not where LAGO would.
      for (Key k : batch.fixed) batch.new_values.setEntry(k, odometry.entry(k));
      std::cout << "mode:        batch (one update from LAGO's initial values, " << lago_seconds
                << " s, chi2 " << chi2(graph.factors, batch.new_values) << ")\n";
      std::cout << "init:        " << describe(lago) << "\n";
    } else {
      std::cout << "mode:        batch (one update from the odometry-composed initial values)\n";
    }
    Stopwatch watch;
    const UpdateResult result = backend->update(batch);
    seconds = watch.seconds();
    iterations = result.iterations;
    if (!result.status.ok()) {
      failures = 1;
      first_failure = std::string(toString(result.status.code)) + ": " + result.status.message;
      worst = result.status.code;
    }
  }
  double after = std::numeric_limits<double>::quiet_NaN();
  try {
    after = chi2(graph.factors, backend->estimate());
  } catch (const Error& e) {
    std::cout << "chi2 after:  not available: " << e.what() << "\n";
  }
  std::cout << std::setprecision(10);
  std::cout << "chi2 before: " << before << "\n";
  if (!std::isnan(after)) std::cout << "chi2 after:  " << after << "\n";
  std::cout << "iterations:  " << iterations << "\n";
  std::cout << std::setprecision(6) << "time:        " << seconds << " s (update calls only)\n";
  if (robust.method != RobustMethod::kLeastSquares) {
    std::size_t closures = 0, rejected = 0;
    for (const FactorPtr& f : model.factors) closures += isLoopClosure(*f);
    const ModelDecisions decisions = modelDecisions(model, *backend, backend->estimate(), robust);
    for (signed char r : decisions.rejected) rejected += r == 1;
    std::cout << "robust:      " << robustMethodName(robust.method) << ", ";
    if (decisions.rejected.empty())
      std::cout << closures << " loop closures (the model gives no per-closure decision)\n";
    else
      std::cout << rejected << " of " << closures << " loop closures rejected\n";
  }
  if (failures == 0)
    std::cout << "status:      ok\n";
  else
    std::cout << "status:      " << failures << " non-ok update(s); worst: " << first_failure
              << "\n";
  if (!FLAGS_output.empty()) {
    writeG2o(FLAGS_output, backend->estimate(), graph.factors, graph.fixed);
    std::cout << "output:      " << FLAGS_output << "\n";
  }
  if (failures == 0) return 0;
  return worst == Status::kUncertain ? 3 : 2;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_solve", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::solve(plugins, positional);
  });
}
