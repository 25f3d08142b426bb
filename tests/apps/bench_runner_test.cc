// The benchmark runner (apps/bench): per-step rows under the thesis protocol,
// chi2 outside the timed region over the dataset's factors, the batch
// optimum, the summary and the result files, and the back-end spec lists of
// the command line (apps/common/cli.h).
#include "apps/bench/bench_runner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/bench/bench_summary.h"
#include "apps/bench/bench_writers.h"
#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "backends/builtins.h"
#include "core/error.h"
#include "core/metrics.h"

namespace hamal::apps {
namespace {

class BenchRunner : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    registry_ = new Registry;
    registerBuiltins(*registry_);
    ManhattanWorldOptions options;
    options.poses = 200;
    options.seed = 11;
    world_ = new ManhattanWorld(generateManhattanWorld(options));
  }
  static void TearDownTestSuite() {
    delete registry_;
    delete world_;
  }
  static Registry* registry_;
  static ManhattanWorld* world_;
};
Registry* BenchRunner::registry_ = nullptr;
ManhattanWorld* BenchRunner::world_ = nullptr;

// Any StepSource feeds the runner (a simulated robot, as FLAG and MOSS
// have): steps are asked for in order, each from the back-end's estimate
// after the previous update, and the factors it marks not_scored stay out of
// chi2.
class RecordingSource : public StepSource {
 public:
  explicit RecordingSource(const Graph& graph) : protocol_(graph) {}
  std::size_t size() const override { return protocol_.size(); }
  Step step(std::size_t i, const Values& estimate) override {
    asked.push_back(i);
    known.push_back(estimate.size());
    return protocol_.step(i, estimate);
  }
  const FactorPtr& prior() const { return protocol_.prior(); }
  std::vector<std::size_t> asked, known;

 private:
  ThesisProtocol protocol_;
};

TEST_F(BenchRunner, RunsAnyStepSourceInOrderFromTheBackendsEstimate) {
  RecordingSource source(world_->graph);
  RunOptions options;
  options.max_steps = 30;
  options.not_scored = {source.prior().get()};
  auto backend = registry_->makeBackend("cholesky");
  const RunResult run = runSteps(source, *backend, "cholesky", options);
  ASSERT_EQ(source.asked.size(), 30u);
  for (std::size_t i = 0; i < 30; ++i) {
    EXPECT_EQ(source.asked[i], i);
    if (i > 0) EXPECT_GT(source.known[i], source.known[i - 1]) << "the estimate grows";
  }
  EXPECT_EQ(source.known[0], 0u);
  auto again = registry_->makeBackend("cholesky");
  const RunResult expect =
      runThesisProtocol(ThesisProtocol(world_->graph), *again, "cholesky", options);
  EXPECT_EQ(run.dataset_factors, expect.dataset_factors);
  EXPECT_DOUBLE_EQ(run.final_chi2, expect.final_chi2);

  RunOptions scored_prior = options;
  scored_prior.not_scored.clear();
  RecordingSource second(world_->graph);
  auto third = registry_->makeBackend("cholesky");
  EXPECT_EQ(runSteps(second, *third, "cholesky", scored_prior).dataset_factors,
            run.dataset_factors + 1);
}

TEST_F(BenchRunner, CholeskyEveryStepEndsAtTheBatchOptimum) {
  const Graph& graph = world_->graph;
  const ThesisProtocol protocol(graph);
  auto backend = registry_->makeBackend("cholesky");
  const RunResult run = runThesisProtocol(protocol, *backend, "cholesky", RunOptions());
  ASSERT_EQ(run.rows.size(), 200u);
  EXPECT_EQ(run.dataset_factors, graph.factors.size());  // the prior is not counted
  for (std::size_t i = 0; i < run.rows.size(); ++i) {
    const StepRow& row = run.rows[i];
    EXPECT_EQ(row.step, i);
    EXPECT_EQ(row.backend, "cholesky");
    EXPECT_EQ(row.status, Status::kOk) << row.status_message;
    EXPECT_GE(row.work.seconds, 0.0);
    ASSERT_TRUE(row.chi2.has_value()) << "chi2_every defaults to every step";
    EXPECT_TRUE(std::isfinite(*row.chi2));
  }
  // Step 0 holds only the first pose and the prior: no dataset factor yet.
  EXPECT_EQ(*run.rows[0].chi2, 0.0);
  EXPECT_EQ(run.final_chi2, *run.rows.back().chi2);
  EXPECT_DOUBLE_EQ(run.final_chi2, chi2(graph.factors, run.estimate));

  const BatchOptimum optimum = solveBatchOptimum(graph, protocol, 0, *registry_, "cholesky");
  ASSERT_TRUE(optimum.status.ok()) << optimum.status.message;
  EXPECT_EQ(optimum.steps, 200u);
  EXPECT_NEAR(run.final_chi2, optimum.chi2, 1e-6 * optimum.chi2);
  // chi2 near its expectation 3 (edges - poses): a real optimum, not a stuck one.
  const double dof = 3.0 * (graph.factors.size() - 200.0 + 1.0);
  EXPECT_NEAR(optimum.chi2, dof, 6 * std::sqrt(2 * dof));

  // --batch's one row: the solve at the last step, with the back-end's own
  // split of its time (left at zero, it read as a solve that took none).
  const StepRow batch_row = batchStepRow(optimum);
  EXPECT_EQ(batch_row.step, 199u);
  EXPECT_EQ(batch_row.backend, "cholesky");
  EXPECT_EQ(batch_row.kind, UpdateKind::kBatch);
  EXPECT_EQ(batch_row.status, Status::kOk);
  EXPECT_EQ(batch_row.work.seconds, optimum.work.seconds);
  EXPECT_EQ(batch_row.work.iterations, optimum.work.iterations);
  EXPECT_EQ(*batch_row.chi2, optimum.chi2);
  EXPECT_GT(batch_row.work.phases.linearize, 0.0);
  EXPECT_GT(batch_row.work.phases.factor, 0.0);
  EXPECT_GT(batch_row.work.phases.solve, 0.0);
  EXPECT_LE(batch_row.work.phases.total(), batch_row.work.seconds);

  const Summary s = summarize("world", {run}, &optimum);
  EXPECT_EQ(s.steps, 200u);
  EXPECT_EQ(s.outcome.non_ok_steps, 0u);
  EXPECT_NEAR(s.accuracy.chi2_ratio, 1.0, 1e-6);
  EXPECT_LE(s.timing.p50, s.timing.p90);
  EXPECT_LE(s.timing.p90, s.timing.p99);
  EXPECT_LE(s.timing.p99, s.timing.max);
  double total = 0;
  for (const auto& row : run.rows) total += row.work.seconds;
  EXPECT_DOUBLE_EQ(s.timing.cumulative_seconds, total);
  EXPECT_GE(s.timing.share_under_100ms, s.timing.share_under_10ms);
}

TEST_F(BenchRunner, Chi2EveryKStepsAndMaxSteps) {
  const ThesisProtocol protocol(world_->graph);
  auto backend = registry_->makeBackend("cholesky");
  RunOptions options;
  options.max_steps = 60;
  options.chi2_every = 7;
  const RunResult run = runThesisProtocol(protocol, *backend, "cholesky", options);
  ASSERT_EQ(run.rows.size(), 60u);
  for (const auto& row : run.rows)
    EXPECT_EQ(row.chi2.has_value(), row.step % 7 == 0 || row.step == 59) << row.step;
  EXPECT_EQ(backend->estimate().size(), 60u);

  // The optimum of the same 60 steps, not of the whole graph.
  const BatchOptimum optimum =
      solveBatchOptimum(world_->graph, protocol, 60, *registry_, "cholesky");
  EXPECT_EQ(optimum.steps, 60u);
  EXPECT_EQ(optimum.estimate.size(), 60u);
  EXPECT_NEAR(run.final_chi2, optimum.chi2, 1e-6 * optimum.chi2);
  const ProtocolPrefix prefix = protocolPrefix(protocol, 60);
  EXPECT_EQ(prefix.factors.size(), run.dataset_factors);
  EXPECT_EQ(prefix.initial.size(), 60u);
}

// A time budget ends the run at the step where the update calls' time
// reaches it, with chi2 at that step; a budget the run stays under changes
// nothing.
TEST_F(BenchRunner, TimeBudgetEndsTheRunAtTheStepThatReachesIt) {
  const ThesisProtocol protocol(world_->graph);
  RunOptions options;
  options.chi2_every = 0;
  auto full_backend = registry_->makeBackend("cholesky");
  const RunResult full = runThesisProtocol(protocol, *full_backend, "cholesky", options);
  ASSERT_EQ(full.rows.size(), protocol.size());
  double total = 0;
  for (const auto& row : full.rows) total += row.work.seconds;

  // Well under the whole run's time: cholesky re-solves everything each step,
  // so the later steps cost most and a tenth of the time ends it early.
  options.time_budget = total / 10;
  auto backend = registry_->makeBackend("cholesky");
  const RunResult cut = runThesisProtocol(protocol, *backend, "cholesky", options);
  ASSERT_TRUE(cut.stopped_by_budget);
  ASSERT_LT(cut.rows.size(), protocol.size());
  double cumulative = 0;
  for (std::size_t i = 0; i + 1 < cut.rows.size(); ++i) cumulative += cut.rows[i].work.seconds;
  EXPECT_LT(cumulative, options.time_budget);
  EXPECT_GE(cumulative + cut.rows.back().work.seconds, options.time_budget);
  ASSERT_TRUE(cut.rows.back().chi2.has_value());
  EXPECT_DOUBLE_EQ(cut.final_chi2, *cut.rows.back().chi2);
  EXPECT_EQ(backend->estimate().size(), cut.rows.size());

  BatchOptimum optimum;
  optimum.backend = "cholesky";
  optimum.chi2 = 1.0;
  const Summary s = summarize("world", {cut}, &optimum);
  EXPECT_TRUE(s.stopped_by_budget);
  EXPECT_EQ(s.steps, cut.rows.size());
  EXPECT_TRUE(std::isnan(s.accuracy.chi2_ratio));  // the optimum is the whole graph's
  std::ostringstream table, csv;
  printSummaryTable(table, {s});
  EXPECT_NE(table.str().find("stopped by the time budget after " + std::to_string(s.steps)),
            std::string::npos)
      << table.str();
  writeSummaryCsv(csv, {s});
  EXPECT_NE(csv.str().find("stopped_by_budget"), std::string::npos);

  options.time_budget = 1e6;
  auto unhurried = registry_->makeBackend("cholesky");
  const RunResult whole = runThesisProtocol(protocol, *unhurried, "cholesky", options);
  EXPECT_FALSE(whole.stopped_by_budget);
  EXPECT_EQ(whole.rows.size(), protocol.size());
  EXPECT_FALSE(summarize("world", {whole}, &optimum).stopped_by_budget);
}

// Repeats that a budget ended at different steps are summarised over the
// steps all of them ran.
TEST(BenchSummary, BudgetedRepeatsUseTheShortestRun) {
  RunResult a, b;
  for (auto* run : {&a, &b}) {
    run->backend = "x";
    for (auto& row : run->rows) row.status = Status::kOk;
  }
  a.rows.resize(3);
  b.rows.resize(2);
  for (auto* run : {&a, &b})
    for (auto& row : run->rows) {
      row.status = Status::kOk;
      row.work.seconds = 0.5;
    }
  b.stopped_by_budget = true;
  a.final_chi2 = 3.0;
  const Summary s = summarize("d", {a, b}, nullptr);
  EXPECT_EQ(s.steps, 2u);
  EXPECT_DOUBLE_EQ(s.timing.cumulative_seconds, 1.0);
  EXPECT_TRUE(std::isnan(s.accuracy.final_chi2));  // a's chi2 is at its step 2, not 1
  b.stopped_by_budget = false;
  EXPECT_THROW(summarize("d", {a, b}, nullptr), Error);
}

TEST_F(BenchRunner, SummaryOfRepeatsUsesMedians) {
  RunResult a, b, c;
  for (auto* run : {&a, &b, &c}) {
    run->backend = "x";
    run->rows.resize(3);
  }
  // Run a takes 1, 2, 3 ms per step; run b 10, 20, 30 ms; run c 100, 2, 3 ms.
  const double t[3][3] = {{0.001, 0.010, 0.100}, {0.002, 0.020, 0.002}, {0.003, 0.030, 0.003}};
  for (int step = 0; step < 3; ++step) {
    for (auto* run : {&a, &b, &c}) run->rows[step].step = step;
    a.rows[step].work.seconds = t[step][0];
    b.rows[step].work.seconds = t[step][1];
    c.rows[step].work.seconds = t[step][2];
  }
  a.rows[1].status = Status::kNumericalFailure;
  a.rows[1].status_message = "singular";
  for (auto* run : {&b, &c})
    for (auto& row : run->rows) row.status = Status::kOk;
  a.rows[0].status = a.rows[2].status = Status::kOk;
  a.final_chi2 = 2.0;
  BatchOptimum optimum;
  optimum.backend = "ref";
  optimum.chi2 = 1.0;
  const Summary s = summarize("d", {a, b, c}, &optimum);
  // Cumulative: median of 0.006, 0.060, 0.105.
  EXPECT_DOUBLE_EQ(s.timing.cumulative_seconds, 0.060);
  // Per-step medians 0.010, 0.002, 0.003.
  EXPECT_DOUBLE_EQ(s.timing.max, 0.010);
  EXPECT_DOUBLE_EQ(s.timing.p50, 0.003);
  EXPECT_NEAR(s.timing.share_under_10ms, 2.0 / 3.0, 1e-15);
  EXPECT_EQ(s.outcome.non_ok_steps, 1u);
  EXPECT_EQ(s.outcome.first_failure, "step 1: numerical_failure: singular");
  EXPECT_DOUBLE_EQ(s.accuracy.chi2_ratio, 2.0);
  EXPECT_EQ(s.repeats, 3);
  // No back-end here computes its estimate apart: update-only is the step time.
  EXPECT_DOUBLE_EQ(s.timing.update_only_seconds, s.timing.cumulative_seconds);
}

// A back-end that computes its estimate apart (PhaseTimes::estimate, as the
// GTSAM plugin's iSAM2 does) gets an update-only time without it, the median
// over the runs, and the table shows the column.
TEST(BenchSummary, UpdateOnlyLeavesTheEstimateOut) {
  RunResult a, b;
  for (auto* run : {&a, &b}) {
    run->backend = "x";
    run->rows.resize(2);
    for (auto& row : run->rows) row.status = Status::kOk;
  }
  a.rows[0].work.seconds = 0.010;
  a.rows[0].work.phases.estimate = 0.004;
  a.rows[1].work.seconds = 0.020;
  a.rows[1].work.phases.estimate = 0.006;
  b.rows[0].work.seconds = 0.030;
  b.rows[0].work.phases.estimate = 0.001;
  b.rows[1].work.seconds = 0.030;
  b.rows[1].work.phases.estimate = 0.001;
  const Summary s = summarize("d", {a, b}, nullptr);
  EXPECT_DOUBLE_EQ(s.timing.cumulative_seconds, (0.030 + 0.060) / 2);
  EXPECT_DOUBLE_EQ(s.timing.update_only_seconds, (0.020 + 0.058) / 2);
  std::ostringstream table;
  printSummaryTable(table, {s});
  EXPECT_NE(table.str().find("update-only s"), std::string::npos) << table.str();
  std::ostringstream csv;
  writeSummaryCsv(csv, {s});
  EXPECT_NE(csv.str().find("update_only_seconds"), std::string::npos);
}

// The bench's summary follows summarizeRows: a later numerical failure is
// the one named, and a run whose last step did not converge has not failed
// (its final chi2 is finite and graded by chi2/opt).
TEST(BenchSummary, NamesTheWorstStatusAndFailsOnlyOnANumericalFailureAtTheEnd) {
  RunResult run;
  run.backend = "x";
  run.rows.resize(4);
  const Status::Code codes[4] = {Status::kOk, Status::kNotConverged, Status::kNumericalFailure,
                                 Status::kNotConverged};
  for (std::size_t i = 0; i < 4; ++i) {
    run.rows[i].step = i;
    run.rows[i].status = codes[i];
    run.rows[i].status_message = i == 2 ? "singular" : "";
  }
  run.final_chi2 = 5.0;
  const Summary s = summarize("d", {run}, nullptr);
  EXPECT_EQ(s.outcome.non_ok_steps, 3u);
  EXPECT_EQ(s.outcome.first_failure, "step 2: numerical_failure: singular");
  EXPECT_FALSE(s.outcome.failed);
  run.rows[3].status = Status::kNumericalFailure;
  EXPECT_TRUE(summarize("d", {run}, nullptr).outcome.failed);
}

TEST(BenchWriters, CsvQuotesSpecsWithCommasAndLeavesMissingChi2Empty) {
  StepRow row;
  row.step = 3;
  row.backend = "ceres:every=2,max_iterations=5";
  row.kind = UpdateKind::kBatch;
  row.status = Status::kOk;
  row.work.seconds = 0.25;
  std::ostringstream os;
  writeRowsCsv(os, {row});
  const std::string text = os.str();
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "run,step,backend,kind,reason,status,status_message,seconds,iterations,"
            "columns_recomputed,variables_relinearized,linearize_seconds,order_seconds,"
            "factor_seconds,solve_seconds,other_seconds,chi2,estimate_seconds");
  EXPECT_NE(
      text.find("0,3,\"ceres:every=2,max_iterations=5\",batch,,ok,,0.25,0,0,0,0,0,0,0,0,,0\n"),
      std::string::npos)
      << text;
  EXPECT_EQ(csvField("a\"b"), "\"a\"\"b\"");
}

TEST(BenchWriters, JsonLinesParseBack) {
  StepRow a, b;
  a.step = 0;
  a.chi2 = 1.5;
  b.step = 1;
  std::ostringstream os;
  writeRowsJsonLines(os, {a, b});
  std::istringstream in(os.str());
  std::string line;
  std::vector<nlohmann::json> parsed;
  while (std::getline(in, line)) parsed.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(parsed.size(), 2u);
  EXPECT_EQ(parsed[0]["chi2"].get<double>(), 1.5);
  EXPECT_TRUE(parsed[1]["chi2"].is_null());
  EXPECT_EQ(parsed[1]["step"].get<int>(), 1);

  Summary s;
  s.backend = "cholesky";
  s.accuracy.optimum_chi2 = std::nan("");
  std::ostringstream js;
  writeSummaryJson(js, {s});
  const auto summary = nlohmann::json::parse(js.str());
  EXPECT_EQ(summary[0]["backend"], "cholesky");
  EXPECT_TRUE(summary[0]["optimum_chi2"].is_null());
}

TEST(BackendSpecList, SemicolonsCommasAndAll) {
  Registry registry;
  registerBuiltins(registry);
  using V = std::vector<std::string>;
  EXPECT_EQ(splitBackendSpecs("ceres;cholesky", registry), (V{"ceres", "cholesky"}));
  EXPECT_EQ(splitBackendSpecs("ceres,cholesky", registry), (V{"ceres", "cholesky"}));
  EXPECT_EQ(splitBackendSpecs("ceres:max_iterations=50,every=2,cholesky", registry),
            (V{"ceres:max_iterations=50,every=2", "cholesky"}));
  EXPECT_EQ(splitBackendSpecs(" ceres:every=2 ; cholesky:max_iterations=3 ", registry),
            (V{"ceres:every=2", "cholesky:max_iterations=3"}));
  const V all = splitBackendSpecs("all", registry);
  EXPECT_EQ(all.size(), registry.backends().size());
  EXPECT_THROW(splitBackendSpecs("every=2,ceres", registry), Error);
  // An option opens no ';' entry: it would join the back-end of another one.
  EXPECT_THROW(splitBackendSpecs("ceres:max_iterations=5;;every=2", registry), Error);
  EXPECT_THROW(splitBackendSpecs("ceres:max_iterations=5;every=2", registry), Error);
  EXPECT_EQ(splitBackendSpecs("ceres;;cholesky;", registry), (V{"ceres", "cholesky"}));
}

TEST(CommandLine, RepeatedFlagsAndDashes) {
  std::vector<std::string> args = {
      "prog", "--plugin=a.so", "-plugin", "b.so,c.so", "--list-backends", "--backend", "x",
      "--",   "--plugin=z"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  EXPECT_EQ(repeatedFlag(int(argv.size()), argv.data(), "plugin"),
            (std::vector<std::string>{"a.so", "b.so,c.so"}));
  normalizeFlagNames(int(argv.size()), argv.data());
  EXPECT_STREQ(argv[4], "--list_backends");
  EXPECT_STREQ(argv[8], "--plugin=z");  // after "--": untouched
}

}  // namespace
}  // namespace hamal::apps
