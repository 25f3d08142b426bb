// ComponentSwitchHook: keeps what R holds of each factor with modes
// (ModeTracking) in step with the estimate. A factor whose mode at the
// estimate differs from the one R holds it linearised with has its
// variables relinearised at the estimate, and every factor on them: the old
// contributions out, the new ones in, the affected rows of R refactored (as
// GTSAM's ISAM2UpdateParams::extraReelimKeys lets a caller ask). Repeats
// while switches appear, a few passes at most.
//
// A pass whose switches are all raised (a nominal + null pair whose null
// mode R holds turning nominal, the usual switch of a new measurement whose
// first guess put it outside the gate) adds the nominal's missing share at
// the linearisation point instead, as rows of a rank update: exact for the
// model linearised there, as a new factor is. When R loses positive
// definiteness a damped batch follows (BatchUpdate).
//
// The factors are read through core/multi_modal.h alone (MultiModal::mode,
// modeInformationScale, modeComponent, isNullHypothesisPair), so a plugin's
// factor with modes switches as a max-mixture does.
#pragma once

#include <vector>

#include "backends/aprilsam/aprilsam_options.h"
#include "backends/aprilsam/batch_update.h"
#include "backends/aprilsam/linearized_graph.h"
#include "backends/aprilsam/visit_stamps.h"
#include "core/backend.h"
#include "core/phase_clock.h"

namespace hamal::aprilsam {

class ComponentSwitchHook {
 public:
  ComponentSwitchHook(const AprilSamOptions& options, LinearizedGraph* graph, BatchUpdate* batch)
      : options_(options), g_(*graph), batch_(*batch) {}

  // The passes after a solve; the reason says what each did. A batch they
  // fall back to is timed on the update's `clock`.
  void run(PhaseClock* clock, UpdateResult* result);

 private:
  // The factors whose mode at the estimate differs from the held one, among
  // those on variables whose dx just changed, into switched_; true when every
  // one is raised (null -> nominal of a null pair).
  bool findSwitches();
  // The raised switches' nominal rows added; false when the passes are over.
  bool raise(PhaseClock* clock, UpdateResult* result);
  // The switched factors' variables relinearised; false when the passes are
  // over.
  bool relinearize(PhaseClock* clock, UpdateResult* result);
  // Null pair f's nominal component, which R holds in its null mode, added
  // at f's linearisation point as rows or into the normal equations.
  bool raiseToNominal(std::size_t f, bool as_rows, UpdateResult* result);
  // After a pass changed R: the new estimate, or, when R lost positive
  // definiteness, a damped batch (false: the passes are over).
  bool solveAfterSwitch(const IncrementalCholesky::Outcome& out, PhaseClock* clock,
                        UpdateResult* result);

  const AprilSamOptions& options_;
  LinearizedGraph& g_;
  BatchUpdate& batch_;
  std::vector<int> switched_, vars_, touched_;  // scratch of the passes
  VisitStamps factor_stamps_, var_stamps_;
};

}  // namespace hamal::aprilsam
