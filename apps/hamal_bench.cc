// hamal_bench: the benchmark runner's executable (docs/PROTOCOL.md, "The
// thesis protocol" and "How to measure"). Runs each back-end over one graph (a file,
// or a synthetic Manhattan world so that it runs with no download) under the
// thesis protocol, timing only the update calls, and compares them: cumulative
// time, per-step p50 / p99 / max, share of steps under 10 ms, final chi2 and
// its ratio to the batch optimum of a reference back-end solved once in the
// same run. Per-step rows and the summary can be written as CSV or JSON.
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "apps/bench/bench_runner.h"
#include "apps/bench/bench_summary.h"
#include "apps/bench/bench_writers.h"
#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "factors/between_factor.h"

DEFINE_string(data, "", "graph file to run on; without it a synthetic world is generated");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_uint64(generate, 0,
              "run on a synthetic Manhattan world of this many poses (default 1000 when no "
              "--data is given)");
DEFINE_uint64(seed, 1, "seed of the synthetic world");
DEFINE_string(backend, "ceres;cholesky",
              "back-ends to compare, by spec, separated by ';' (a ',' works too, except inside "
              "a spec's options: \"ceres:max_iterations=50,every=2;cholesky\"), or the flag "
              "repeated; \"all\" is every registered back-end");
HAMAL_FLAG_ALIAS(backends, backend);
DEFINE_string(reference, "cholesky",
              "back-end whose batch solve (from --init's values) gives the optimum chi2 that "
              "final chi2 is compared with; \"none\" to skip");
DEFINE_string(rows, "", "write per-step rows here: .csv, or .jsonl for JSON lines");
DEFINE_string(summary, "", "write the summary here: .csv or .json");
DEFINE_int32(repeat, 1,
             "run each back-end this many times, in turns (run 1 of every back-end, then run 2, "
             "...); times are medians over the runs");
DEFINE_uint64(max_steps, 0, "stop after this many steps (0: all)");
DEFINE_double(time_budget, 0,
              "stop a back-end's run once its update calls have taken this many seconds (0: "
              "no budget): for a side-by-side scale run where one back-end would take hours, "
              "its cumulative-time curve up to the budget (rows) against the others' whole "
              "runs; such a run has no chi2/opt, and the summary says it stopped");
DEFINE_uint64(chi2_every, 1, "compute chi2 every k steps (and at the last); 0: last step only");
DEFINE_string(residual, "thesis", "residual of the between factors: thesis | measurement");
DEFINE_bool(batch, false,
            "solve each back-end once on the whole graph (the first --max_steps steps) from "
            "--init's values (docs/PROTOCOL.md, batch solves), instead of the "
            "protocol's one update per pose; one row per back-end");
DEFINE_string(
    init, "odometry",
    "initial values of the batch solves (--batch and --reference): odometry (composed, "
    "docs/PROTOCOL.md) or lago (linear orientation-then-position estimate, for worlds whose "
    "odometry drifts too far for Gauss-Newton; its time is printed, not counted)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "compares back-ends under the thesis protocol (one update per pose).\n\n"
    "  hamal_bench                                   # 1000-pose synthetic world, ceres and "
    "cholesky\n"
    "  hamal_bench --data M3500.toro --backend \"ceres;cholesky\" --rows rows.csv --summary "
    "s.json\n"
    "  hamal_bench --generate 3500 --backend ceres:every=10 --backend cholesky --repeat 3\n\n"
    "Only the update calls are timed (steady clock); chi2 is over the dataset's factors\n"
    "(not the protocol's prior), computed outside the timed region. chi2/opt is the final\n"
    "chi2 over the batch optimum of --reference, solved once from odometry (or from LAGO's\n"
    "estimate with --init lago).\n\n"
    "Exit status: 0 when at least one back-end ended ok, 1 an error (bad input or options),\n"
    "2 when every back-end ended in a failure (its last step not ok or its chi2 not finite).";

int bench(const std::vector<std::string>& plugins, const std::vector<std::string>& backend_flags,
          const std::vector<std::string>& positional) {
  Registry registry;
  setUpRegistry(registry, plugins);
  if (printListings(registry)) return 0;
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_repeat < 1) throw Error("--repeat must be at least 1");
  if (!FLAGS_data.empty() && FLAGS_generate) throw Error("give --data or --generate, not both");

  std::vector<std::string> specs;
  for (const auto& flag :
       backend_flags.empty() ? std::vector<std::string>{FLAGS_backend} : backend_flags)
    for (std::string& spec : splitBackendSpecs(flag, registry)) specs.push_back(std::move(spec));
  if (specs.empty()) throw Error("no back-end to run (see --backend and --list-backends)");
  // Every spec checked before anything runs: names and option names here,
  // option values by the back-end made from them.
  for (const auto& spec : specs) registry.makeBackend(spec);
  const bool with_reference = FLAGS_reference != "none" && !FLAGS_reference.empty();
  if (with_reference) registry.makeBackend(FLAGS_reference);
  const BetweenResidual residual = parseResidual(FLAGS_residual);
  const Initialization init = parseInitialization(FLAGS_init);
  checkOutputPaths({{"rows", FLAGS_rows}, {"summary", FLAGS_summary}}, {{"data", FLAGS_data}});

  Graph graph;
  std::string dataset;
  if (!FLAGS_data.empty()) {
    graph = readGraph(FLAGS_data, registry, parseFormat(FLAGS_format));
    dataset = FLAGS_data;
  } else {
    ManhattanWorldOptions world_options;
    world_options.poses = FLAGS_generate ? FLAGS_generate : 1000;
    world_options.seed = FLAGS_seed;
    ManhattanWorld world = generateManhattanWorld(world_options);
    std::cout << "synthetic Manhattan world: " << world_options.poses << " poses, "
              << world.odometry_edges << " odometry edges, " << world.loop_closures
              << " loop closures, seed " << world_options.seed << "\n";
    graph = std::move(world.graph);
    dataset = graph.source;
  }
  setBetweenResidual(graph, residual);
  const ThesisProtocol protocol(graph);
  RunOptions run_options;
  run_options.max_steps = FLAGS_max_steps;
  run_options.chi2_every = FLAGS_chi2_every;
  if (!(FLAGS_time_budget >= 0) || !std::isfinite(FLAGS_time_budget))
    throw Error("--time_budget must be a finite number of seconds >= 0");
  run_options.time_budget = FLAGS_time_budget;
  const std::size_t steps = run_options.max_steps
                                ? std::min<std::size_t>(run_options.max_steps, protocol.size())
                                : protocol.size();
  std::cout << "dataset: " << dataset << ": " << graph.factors.size() << " factors, "
            << protocol.size() << " steps (running " << steps << "), "
            << betweenResidualName(residual) << " residual\n";

  BatchOptimum optimum;
  if (with_reference) {
    optimum = solveReference(graph, protocol, steps, registry, FLAGS_reference, init);
    if (!optimum.init.report.empty()) std::cout << optimum.init.report << "\n";
    if (!optimum.note.empty()) std::cout << "reference: " << optimum.note << "\n";
    std::cout << std::setprecision(10) << "batch optimum (" << optimum.backend << ", from "
              << initializationName(optimum.init.from) << "): chi2 " << optimum.chi2
              << std::setprecision(4) << ", " << optimum.work.seconds << " s, "
              << optimum.work.iterations << " iterations, "
              << (optimum.status.ok()
                      ? "ok"
                      : std::string(toString(optimum.status.code)) + ": " + optimum.status.message)
              << "\n";
  }

  std::vector<Summary> summaries;
  std::vector<StepRow> all_rows;
  if (FLAGS_batch) {
    for (const auto& spec : specs) {
      // For graphs too big to re-solve at every step (the scale study): the
      // time of one batch update, as a summary of one step.
      std::cerr << "batch solve " << spec << "..." << std::flush;
      const BatchOptimum batch = solveBatchOptimum(graph, protocol, steps, registry, spec, init);
      std::cerr << " " << batch.work.seconds << " s";
      if (init == Initialization::kLago)
        std::cerr << " (from LAGO: " << batch.init.seconds << " s, chi2 " << batch.init.chi2 << "; "
                  << batch.init.report << ")";
      std::cerr << "\n";
      RunResult run;
      run.backend = spec;
      const StepRow row = batchStepRow(batch);
      run.rows.push_back(row);
      run.final_chi2 = batch.chi2;
      summaries.push_back(summarize(dataset, {run}, with_reference ? &optimum : nullptr));
      all_rows.push_back(row);
    }
  } else {
    // Run r of every back-end before run r + 1 of any: a machine whose speed
    // drifts during the invocation (a shared VM varies by 2x over minutes)
    // then slows every back-end's median alike, and a ratio of medians
    // compares like with like.
    std::vector<std::vector<RunResult>> runs(specs.size());
    for (int r = 0; r < FLAGS_repeat; ++r)
      for (std::size_t b = 0; b < specs.size(); ++b) {
        const std::string& spec = specs[b];
        std::cerr << "running " << spec << " (run " << r + 1 << " of " << FLAGS_repeat << ")..."
                  << std::flush;
        RunOptions options = run_options;
        if (r > 0) options.chi2_every = 0;  // chi2 is the first run's; later runs are for time
        std::unique_ptr<Backend> backend = registry.makeBackend(spec);
        runs[b].push_back(runThesisProtocol(protocol, *backend, spec, options, r));
        double total = 0;
        for (const auto& row : runs[b].back().rows) total += row.work.seconds;
        std::cerr << " " << total << " s\n";
      }
    for (auto& spec_runs : runs) {
      summaries.push_back(summarize(dataset, spec_runs, with_reference ? &optimum : nullptr));
      if (!FLAGS_rows.empty())
        for (auto& run : spec_runs)
          all_rows.insert(all_rows.end(), run.rows.begin(), run.rows.end());
    }
  }
  std::cout << "\n";
  printSummaryTable(std::cout, summaries);
  if (!FLAGS_rows.empty()) {
    writeRowsFile(FLAGS_rows, all_rows);
    std::cout << "rows: " << FLAGS_rows << "\n";
  }
  if (!FLAGS_summary.empty()) {
    writeSummaryFile(FLAGS_summary, summaries);
    std::cout << "summary: " << FLAGS_summary << "\n";
  }
  // Like hamal_solve's numerical failure: a comparison with nothing to
  // compare is not a success.
  if (std::all_of(summaries.begin(), summaries.end(),
                  [](const Summary& s) { return s.outcome.failed; })) {
    std::cerr << "hamal_bench: every back-end failed (see the table)\n";
    return 2;
  }
  return 0;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_bench", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto backends = hamal::apps::repeatedFlag(argc, argv, "backend");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::bench(plugins, backends, positional);
  });
}
