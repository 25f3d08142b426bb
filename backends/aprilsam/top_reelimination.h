// TopReelimination: hamal's alternative to AprilSAM's batch (reeliminate=
// top; not in the thesis, iSAM2's way, Kaess et al., IJRR 2012): instead of
// relinearising, reordering and refactoring everything (Alg. 3.1 lines
// 12-16) a batch decision re-eliminates only the top of R
// (IncrementalCholesky::topOf, reorderTop): the rows that the factors added
// since the last re-elimination and the variables in L (and those within
// top_relinearize of it) reach, with their elimination-tree ancestors,
// reordered by the min-heap ordering (Alg. 3.2) on the top's graph with
// each kept subtree's separator as a clique, and refactored. The variables
// in the top that no factor ties to a kept row move their linearisation
// points to the estimate. Every row is then solved, as after a batch.
//
// It does not apply (the caller batches instead) to factors with modes,
// after a damped batch, for a top of more than top_share of the rows, or a
// top that is not positive definite; then nothing is changed that a batch
// does not redo (and a top over top_share after batches that made no
// progress may wait instead: top_backoff.h).
#pragma once

#include <string>
#include <vector>

#include "backends/aprilsam/aprilsam_options.h"
#include "backends/aprilsam/linearized_graph.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/aprilsam/ordering_input.h"
#include "backends/aprilsam/visit_stamps.h"
#include "core/backend.h"
#include "core/phase_clock.h"

namespace hamal::aprilsam {

class TopReelimination {
 public:
  TopReelimination(const AprilSamOptions& options, LinearizedGraph* graph,
                   OrderingWorkspace* workspace)
      : options_(options), g_(*graph), workspace_(*workspace) {}

  // The top re-eliminated, its phases timed on the update's `clock`; false
  // when it does not apply (see above).
  bool run(const std::string& reason, PhaseClock* clock, UpdateResult* result);
  // Whether variable v is due for relinearisation: in L, or moved by
  // top_relinearize x delta_T from its linearisation point (one that
  // settles just below delta_T would otherwise never be).
  bool due(int v) const;
  // Whether the last run() did not apply because the top was over top_share.
  bool oversized() const { return oversized_; }

 private:
  // The top's rows, ascending; empty when there is none.
  std::vector<int> chooseTop() const;
  // The factors on the top into fs_ (local_: a variable's index in the
  // top); the top's variables no such factor ties to a kept row move to
  // the estimate. Their count.
  long relinearizeFree(const std::vector<int>& top);
  // The top's new order (rows of R) by the min-heap ordering, and each top
  // variable's rank in it.
  std::vector<int> orderTop(const std::vector<int>& top, std::vector<int>* rank);
  // H of the top's factors at the top's new positions into the normal
  // equations; false when a factor or their cost is not finite.
  bool linearizeTop(const std::vector<int>& rank, int kept, UpdateResult* result);

  const AprilSamOptions& options_;
  LinearizedGraph& g_;
  OrderingWorkspace& workspace_;
  std::vector<int> local_;      // v -> index in the top, -1 outside
  std::vector<int> fs_;         // the factors on the top
  VisitStamps stamps_;          // of the factors, while fs_ is gathered
  std::vector<int> positions_;  // v -> column block of the top's H, for its factors' v
  // The top's graph, its lists kept between tops (a top of thousands of
  // variables grew as many lists from nothing, a fifth of its ordering's
  // cost), and the lists a smaller top leaves over.
  OrderingInput top_graph_;
  std::vector<std::vector<int>> spare_lists_;
  bool oversized_ = false;  // the last run's top was over top_share
};

}  // namespace hamal::aprilsam
