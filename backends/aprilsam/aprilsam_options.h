// AprilSamOptions: AprilSAM's options (thesis ch. 3, Alg. 3.1 and sec.
// 3.4), parsed once when the back-end is made: the choices are enums, so no
// step compares option strings; each option's meaning is in optionSpecs().
#pragma once

#include <vector>

#include "backends/aprilsam/update_policy.h"
#include "core/dormant_policy.h"
#include "core/options.h"

namespace hamal::aprilsam {

struct AprilSamOptions {
  enum class Ordering { kMinHeap, kBhamd, kAmd, kNatural };  // minheap, bhamd, amd, natural
  enum class FactorUpdate { kRank, kRefactor };              // rank, refactor
  enum class Backsolve { kPartial, kFull };                  // partial, full
  enum class Reeliminate { kFull, kTop };                    // full, top

  // The back-substitution's (PartialBacksolve): backsolve, backsolve_tolerance.
  struct BacksolveOptions {
    Backsolve kind = Backsolve::kPartial;  // full: AprilSAM-FullSolve
    double tolerance = 1e-3;               // propagate dx changes larger than this
  };
  // The batch's (BatchUpdate): batch_iterations, damping.
  struct BatchOptions {
    long iterations = 1;    // Gauss-Newton steps per batch update
    double damping = 1e-4;  // lambda of the damped fallback batch
  };
  // The top re-elimination's (TopReelimination): top_share, top_relinearize.
  struct TopOptions {
    double share = 0.5;        // a larger top (share of R's rows) batches
    double relinearize = 0.3;  // relinearise |dx_i| >= this x delta_T too
    long backoff = 64;         // the longest hold of a batch that made no progress (top_backoff.h)
  };

  UpdatePolicyOptions policy;
  Ordering ordering = Ordering::kMinHeap;
  double loop_closure_radius = 5.0;                  // R_T (eq. 3.20 and n_lc), metres
  long n_lc = 3;                                     // fixed n_lc; 0: count the nodes within R_T
  FactorUpdate factor_update = FactorUpdate::kRank;  // addRows | eq. 3.14
  long rank_update_max_rows = 64;                    // more new rows than this: refactor
  BacksolveOptions backsolve;
  BatchOptions batch;
  bool batch_first = false;  // cost and periodic criteria before the incremental update
  double dormant_scale = DormantPolicy::kDefaultScale;  // core/dormant_policy.h
  Reeliminate reeliminate = Reeliminate::kFull;         // what a batch decision re-eliminates
  TopOptions top;                                       // reeliminate=top

  static std::vector<OptionSpec> optionSpecs();
  // Throws hamal::Error naming a bad option.
  static AprilSamOptions fromOptions(const Options& options);
};

}  // namespace hamal::aprilsam
