// The grid behind COUNTPOSSIBLELOOPCLOSURENODES (Alg. 3.1 line 10, n_lc=0)
// at negative and far-off coordinates: a cell key made by shifting a negative
// coordinate left would be undefined behaviour, which the sanitizer build of
// this suite reports. The runs
// here put the trajectory in each quadrant and far out, and ask for the same
// batch decisions as at the origin.
#include "backends/aprilsam/loop_closure_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/metrics.h"
#include "protocol/thesis_protocol.h"
#include "tests/aprilsam/aprilsam_test_graphs.h"

namespace hamal::aprilsam::testing {
namespace {

// The graph moved by (dx, dy): the protocol composes every pose from x0's
// initial value, which its prior holds, so moving x0 moves everything.
struct GridRun {
  int batches = 0;
  bool all_ok = true;
};

GridRun runShifted(double dx, double dy) {
  RandomGraphOptions o;
  o.poses = 80;
  o.seed = 5;
  Graph g = randomGraph(o);
  g.initial.insert(X(0), Pose2(dx, dy, 0));  // the protocol's prior, where x0 starts
  const ThesisProtocol protocol(g);
  auto backend = makeAprilSam({{"n_lc", "0"}, {"loop_closure_radius", "2"}});
  GridRun run;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    run.all_ok = run.all_ok && r.status.ok();
  }
  run.batches = backend->batches();
  return run;
}

TEST(LoopClosureGrid, CountsNodesInEveryQuadrantAndFarOut) {
  const GridRun origin = runShifted(0, 0);
  ASSERT_TRUE(origin.all_ok);
  EXPECT_GT(origin.batches, 1);
  for (const auto& [dx, dy] : std::vector<std::pair<double, double>>{
           {-100, -100}, {-100, 100}, {100, -100}, {-3e9, 7e9}}) {
    SCOPED_TRACE(std::to_string(dx) + ", " + std::to_string(dy));
    const GridRun moved = runShifted(dx, dy);
    EXPECT_TRUE(moved.all_ok);
    // Rounding of the moved coordinates may tip a distance across R_T.
    EXPECT_NEAR(moved.batches, origin.batches, 2);
  }
}

// A map whose estimate wanders (a diverging robust solve on ais2klinik)
// left one empty cell per place it had been, and every batch's refile
// cleared them all: aprilsam-top with GNC spent over half its time there.
// After a refile the cells stay within about three times the variables, and the
// count is still the brute force's.
TEST(LoopClosureGrid, RefilesKeepTheCellsBoundedAndTheCountRight) {
  LoopClosureGrid grid(1.0, 0);
  std::vector<Values::Entry> lin(10);
  for (int round = 0; round < 200; ++round) {
    for (int v = 0; v < 10; ++v) {
      Values::Entry e;
      e.type = VariableType::kPose2;
      e.data = {1000.0 * round + 0.3 * v, -500.0 * round, 0};
      lin[v] = e;
    }
    grid.refile(lin);
    EXPECT_LE(grid.cells(), 3 * lin.size() + 64);  // twice, plus one refile's new cells
  }
  long brute = 0;
  for (int v = 0; v < 9; ++v)
    brute += std::hypot(lin[v].data[0] - lin[9].data[0], lin[v].data[1] - lin[9].data[1]) < 1.0;
  EXPECT_EQ(grid.countPossibleLoopClosureNodes(9, lin), brute);
  EXPECT_GT(brute, 0);
}

// With a fixed n_lc (the default) or no radius the count never reads the
// cells, so nothing is filed: a robust run on ais2klinik batches at almost
// every step, and refiling 15000 variables each time was a twentieth of it.
TEST(LoopClosureGrid, FilesNothingWhenTheCountDoesNotReadTheCells) {
  std::vector<Values::Entry> lin(10);
  for (int v = 0; v < 10; ++v) {
    lin[v].type = VariableType::kPose2;
    lin[v].data = {0.1 * v, 0, 0};
  }
  LoopClosureGrid fixed(1.0, 3), no_radius(0.0, 0), counting(1.0, 0);
  for (LoopClosureGrid* grid : {&fixed, &no_radius, &counting}) {
    for (int v = 0; v < 10; ++v) grid->insert(v, lin[v]);
    grid->refile(lin);
  }
  EXPECT_EQ(fixed.cells(), 0u);
  EXPECT_EQ(no_radius.cells(), 0u);
  EXPECT_GT(counting.cells(), 0u);
  EXPECT_EQ(fixed.countPossibleLoopClosureNodes(9, lin), 3);
  EXPECT_EQ(no_radius.countPossibleLoopClosureNodes(9, lin), 0);
  EXPECT_EQ(counting.countPossibleLoopClosureNodes(9, lin), 9);
}

}  // namespace
}  // namespace hamal::aprilsam::testing
