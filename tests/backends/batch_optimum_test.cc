// The batch optimum on the public datasets (docs/PROTOCOL.md, "Batch solves"):
// one update with the whole graph (ThesisProtocol::batch, from odometry)
// must reach the reference chi2 within 0.1% with both batch back-ends
// (ceres and cholesky, thesis sec. 3.5.1), and the two must agree within
// 0.1%. chi2 is over the dataset's factors only, not the protocol's prior.
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <string>

#include "backends/builtins.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "core/stopwatch.h"
#include "protocol/thesis_protocol.h"
#include "tests/testing/test_data.h"

namespace hamal {
namespace {

struct Reference {
  const char* file;
  double chi2;
};

class BatchOptimum : public ::testing::TestWithParam<Reference> {};

double solve(const Registry& registry, const std::string& spec, const Graph& graph,
             const Step& batch) {
  auto backend = registry.makeBackend(spec);
  Stopwatch watch;
  const UpdateResult r = backend->update(batch);
  const double seconds = watch.seconds();
  EXPECT_TRUE(r.status.ok()) << spec << ": " << r.status.message;
  EXPECT_EQ(r.kind, UpdateKind::kBatch);
  const double value = chi2(graph.factors, backend->estimate());
  std::cout << std::setprecision(8) << "[ figures  ] " << graph.source << " " << spec << ": chi2 "
            << value << ", " << seconds << " s, " << r.iterations << " iterations (linearize "
            << r.time.linearize << " s, order " << r.time.order << " s, factor " << r.time.factor
            << " s, solve " << r.time.solve << " s)\n";
  return value;
}

TEST_P(BatchOptimum, BothBackendsReachTheReferenceChi2) {
  const Reference ref = GetParam();
  HAMAL_REQUIRE_DATA(path, ref.file);
  Registry registry;
  registerBuiltins(registry);
  const Graph graph = readGraph(path, registry);
  const Step batch = ThesisProtocol(graph).batch();

  const double ceres = solve(registry, "ceres", graph, batch);
  const double cholesky = solve(registry, "cholesky", graph, batch);
  EXPECT_NEAR(ceres, ref.chi2, 1e-3 * ref.chi2) << ref.file;
  EXPECT_NEAR(cholesky, ref.chi2, 1e-3 * ref.chi2) << ref.file;
  EXPECT_NEAR(ceres, cholesky, 1e-3 * std::min(ceres, cholesky)) << ref.file;
}

INSTANTIATE_TEST_SUITE_P(PublicData, BatchOptimum,
                         ::testing::Values(Reference{"M3500.toro", 137.91295},
                                           Reference{"intel.g2o", 44.41781},
                                           Reference{"manhattan.g2o", 3533.4585},
                                           Reference{"city10000.g2o", 511.98516},
                                           Reference{"CSAIL.g2o", 61.14297}),
                         [](const ::testing::TestParamInfo<Reference>& info) {
                           return ::hamal::testing::testName(info.param.file);
                         });

}  // namespace
}  // namespace hamal
