// BatchUpdate: lines 12-16 of Alg. 3.1 (thesis sec. 3.4.4): every
// linearisation point moves to the estimate (UPDATELINEARIZATIONPOINT), the
// variables are reordered (sec. 3.4.3: min-heap, BHAMD, AMD or natural),
// R and y are factored from scratch (BATCHUPDATE) and solved
// (BACKWARDSUBSTITUTE): ONE Gauss-Newton step as in the thesis and its
// reference code; batch_iterations > 1 repeats it.
//
// The variable graph the orderings read is grown with each factor, so a
// batch does not rebuild it; the factors with modes stay out of it and each
// batch adds the edges of those not dormant at the new linearisation points
// to a copy (ModeTracking).
//
// A factorisation that meets a block that is not positive definite is
// retried with Levenberg-style damping (A_ii += lambda diag(A_ii)), which
// the reason says; when that fails too the Status names the variable and
// the next update batches again (BatchRecord::broken).
#pragma once

#include <string>
#include <vector>

#include "backends/aprilsam/aprilsam_options.h"
#include "backends/aprilsam/linearized_graph.h"
#include "backends/aprilsam/loop_closure_grid.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/aprilsam/ordering_input.h"
#include "core/backend.h"
#include "core/phase_clock.h"

namespace hamal::aprilsam {

class BatchUpdate {
 public:
  BatchUpdate(const AprilSamOptions& options, LinearizedGraph* graph, LoopClosureGrid* grid,
              OrderingWorkspace* workspace)
      : options_(options), g_(*graph), grid_(*grid), workspace_(*workspace) {}

  // The orderings' graph grows with the graph: a new variable, and the
  // edges of new factor f (a factor with modes joins each batch instead).
  void addVariable() { ordering_input_.adjacency.emplace_back(); }
  void addFactorEdges(int f);

  // The batch; `reason` says why, `damped` starts it damped. Its phases
  // are timed on the update's `clock`. The batch takes batch_iterations
  // Gauss-Newton steps (the thesis takes one); steps that end with a
  // (weighted) chi2 above the one they started from are kNotConverged,
  // never ok: one step from a poor guess can overshoot by orders of
  // magnitude.
  void run(const std::string& reason, bool damped, PhaseClock* clock, UpdateResult* result);
  int batches() const { return batches_; }

 private:
  // The batch's order of the free variables, laid out in the graph (pos_of,
  // var_at, R and dx resized); their dimensions in that order.
  std::vector<int> layOutOrder();
  std::vector<int> computeOrdering();
  // One Gauss-Newton step at the linearisation points, damped from the
  // start when *damped, with the damping *lambda raised until R exists;
  // false when it failed (the graph is then broken). Its phases' times go
  // to `result` through `clock`.
  bool iterate(const std::vector<int>& dims, bool* damped, double* lambda, PhaseClock* clock,
               UpdateResult* result);

  const AprilSamOptions& options_;
  LinearizedGraph& g_;
  LoopClosureGrid& grid_;
  OrderingWorkspace& workspace_;  // the min-heap ordering's lists, reused
  OrderingInput ordering_input_, moded_ordering_input_;
  int batches_ = 0;
};

}  // namespace hamal::aprilsam
