// Tests of the partial back-substitution (thesis sec. 3.4.2, fig. 3.7): with
// backsolve_tolerance = 0 it is bit for bit the full solve (AprilSAM-FullSolve);
// with a tolerance it solves fewer rows and stays close.
#include "backends/aprilsam/partial_backsolve.h"

#include <gtest/gtest.h>

#include "tests/aprilsam/aprilsam_test_graphs.h"

namespace hamal::aprilsam {
namespace {

using testing::makeAprilSam;
using testing::randomGraph;
using testing::RandomGraphOptions;

struct Outcome {
  Values estimate;
  long rows_solved = 0;
};

Outcome run(const Graph& graph, std::map<std::string, std::string> options) {
  auto be = makeAprilSam(options);
  ThesisProtocol protocol(graph);
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = be->update(protocol.step(i, be->estimate()));
    EXPECT_TRUE(r.status.ok());
  }
  return {be->estimate(), be->backsolve().rowsSolved()};
}

TEST(PartialBacksolve, ExactWithZeroToleranceEqualsFullSolve) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    RandomGraphOptions o;
    o.poses = 100;
    o.landmarks = 6;
    o.seed = seed;
    const Graph g = randomGraph(o);
    const Outcome partial = run(g, {{"backsolve", "partial"}, {"backsolve_tolerance", "0"}});
    const Outcome full = run(g, {{"backsolve", "full"}});
    ASSERT_EQ(partial.estimate.size(), full.estimate.size());
    for (const Key& k : full.estimate.keys()) {
      const auto& a = partial.estimate.entry(k).data;
      const auto& b = full.estimate.entry(k).data;
      for (int t = 0; t < 3; ++t) EXPECT_EQ(a[t], b[t]) << k << "[" << t << "]";
    }
  }
}

TEST(PartialBacksolve, ToleranceSolvesFewerRowsAndStaysClose) {
  RandomGraphOptions o;
  o.poses = 150;
  o.seed = 5;
  const Graph g = randomGraph(o);
  // Incremental mode: no batch resets the rows in between.
  const Outcome exact = run(g, {{"mode", "incremental"}, {"backsolve_tolerance", "0"}});
  const Outcome loose = run(g, {{"mode", "incremental"}, {"backsolve_tolerance", "1e-4"}});
  EXPECT_LT(loose.rows_solved, exact.rows_solved);
  double worst = 0;
  for (const Key& k : exact.estimate.keys())
    for (int t = 0; t < 3; ++t)
      worst = std::max(
          worst, std::fabs(exact.estimate.entry(k).data[t] - loose.estimate.entry(k).data[t]));
  EXPECT_LT(worst, 1e-2);
}

}  // namespace
}  // namespace hamal::aprilsam
