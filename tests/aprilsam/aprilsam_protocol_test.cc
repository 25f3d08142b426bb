// AprilSAM and its thesis variants (sec. 3.5.1) under the thesis protocol on
// the public datasets: the final chi2 (over the dataset's factors, the
// protocol's prior excluded) against the batch optimum (docs/PROTOCOL.md,
// "Reference optima").
// city10000 is benchmark-only (hamal_bench): its periodic runs take over a
// minute each here.
#include <gtest/gtest.h>

#include <string>

#include "backends/builtins.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "protocol/thesis_protocol.h"
#include "tests/testing/test_data.h"

namespace hamal {
namespace {

struct Run {
  double chi2 = 0;
  int batches = 0;
  int incremental = 0;
  int early_tops = 0;  // top re-eliminations the time criterion called before the rank update
};

Run runProtocol(const std::string& path, const std::string& spec) {
  Registry registry;
  registerBuiltins(registry);
  const Graph graph = readGraph(path, registry);
  ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend(spec);
  Run run;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    EXPECT_TRUE(r.status.ok()) << spec << " step " << i << ": " << r.status.message;
    if (r.kind == UpdateKind::kBatch) ++run.batches;
    if (r.kind == UpdateKind::kIncremental) ++run.incremental;
    if (r.reason.rfind("incremental cost x n_lc", 0) == 0 &&
        r.reason.find("top re-eliminated") != std::string::npos)
      ++run.early_tops;
    EXPECT_EQ(r.variables, backend->estimate().size());
    EXPECT_GT(r.columns_recomputed, 0u);
    // A batch step also did the incremental update before it (Alg. 3.1).
    if (r.kind == UpdateKind::kIncremental) EXPECT_LE(r.columns_recomputed, r.columns_total);
    if (r.kind == UpdateKind::kBatch) EXPECT_GE(r.columns_recomputed, r.columns_total);
  }
  run.chi2 = chi2(graph.factors, backend->estimate());
  return run;
}

void expectNearOptimum(const std::string& file, double optimum, const std::string& spec,
                       double relative) {
  HAMAL_REQUIRE_DATA(path, file);
  const Run run = runProtocol(path, spec);
  EXPECT_GT(run.incremental, run.batches) << spec;
  EXPECT_GE(run.chi2, optimum * (1 - 1e-6)) << spec;
  EXPECT_LE(run.chi2, optimum * (1 + relative)) << spec << " on " << file;
}

constexpr double kM3500 = 137.91295;
constexpr double kIntel = 44.41781;
constexpr double kManhattan = 3533.4585;

TEST(AprilSamProtocol, M3500Adaptive) { expectNearOptimum("M3500.toro", kM3500, "aprilsam", 1e-3); }
TEST(AprilSamProtocol, M3500FullSolve) {
  expectNearOptimum("M3500.toro", kM3500, "aprilsam-fullsolve", 1e-3);
}
// The periodic variants at their default k=10. (With the thesis' k=50 they
// end with up to 49 unrelinearised steps after the last batch, sec. 3.5.2,
// and land 0.3% above the optimum on M3500, 19.8% on manhattan.)
TEST(AprilSamProtocol, M3500Periodic) {
  expectNearOptimum("M3500.toro", kM3500, "aprilsam-periodic", 1e-3);
}
TEST(AprilSamProtocol, M3500NoPredictiveOrder) {
  expectNearOptimum("M3500.toro", kM3500, "aprilsam-nopredictive", 1e-3);
}
// aprilsam-top (hamal's, iSAM2's re-elimination of the top instead of
// batches) ends within 1e-4 of the optimum, its accuracy target.
TEST(AprilSamProtocol, M3500Top) { expectNearOptimum("M3500.toro", kM3500, "aprilsam-top", 1e-4); }
// batch_first with reeliminate=top: a time criterion met before the rank
// update re-eliminates the top without it, rather than running a batch.
TEST(AprilSamProtocol, M3500TopBatchFirst) {
  HAMAL_REQUIRE_DATA(path, "M3500.toro");
  const auto run = runProtocol(path, "aprilsam-top:batch_first=true");
  EXPECT_GT(run.early_tops, 20);
  EXPECT_LT(run.batches, run.early_tops);
  EXPECT_LE(run.chi2, kM3500 * (1 + 1e-4));
}
TEST(AprilSamProtocol, IntelAllVariants) {
  for (const char* spec : {"aprilsam", "aprilsam-fullsolve", "aprilsam-periodic",
                           "aprilsam-nopredictive", "aprilsam-top"})
    expectNearOptimum("intel.g2o", kIntel, spec, 1e-3);
}
// manhattan.g2o: where a stale linearisation costs most (k=50: +19.8%).
TEST(AprilSamProtocol, ManhattanAllVariants) {
  for (const char* spec : {"aprilsam", "aprilsam-fullsolve", "aprilsam-periodic",
                           "aprilsam-nopredictive", "aprilsam-top"})
    expectNearOptimum("manhattan.g2o", kManhattan, spec, 1e-3);
}

}  // namespace
}  // namespace hamal
