// UpdatePolicy: AprilSAM's choice between an incremental and a batch update
// (thesis sec. 3.4.4, Alg. 3.1 lines 4-11), and the periodic policy of the
// AprilSAM-Periodic variant (sec. 3.5.1).
//
// After the incremental update of a step, Alg. 3.1 batches (relinearises
// everything, reorders, refactors) when
//   1. |L| >= NL_T, L = the nodes whose change |dx_i| >= delta_T;
//   2. ||dx|| >= Delta_T, the norm of the whole state change;
//   3. RUNTIME(incremental) x n_lc >= RUNTIME(batch), n_lc = the nodes
//      within R_T of the newest pose that a loop closure may soon touch.
// The thesis writes >= in Alg. 3.1 and > in its text; this follows Alg. 3.1.
//
// Conventions the back-end and this class share:
// - |dx_i| is the infinity norm of node i's block of dx (the largest change
//   of any coordinate, as GTSAM's relinearizeThreshold compares it);
//   ||dx|| is the 2-norm of the whole dx. The back-end counts |L| and
//   passes it as `moved_nodes`.
// - A NaN or infinite ||dx|| meets criterion 2 (relinearising is the cure).
// - Step 0 (the first update) is always a batch, in every mode: there is
//   no factor or ordering to update yet.
// - Criterion 3 needs a batch cost: it is skipped while costs.batch <= 0.
// - Costs are seconds (cost=wallclock, as the thesis) or flops predicted
//   from the factor's column counts (cost=deterministic, the default, see
//   factorization_cost.h) so that runs are reproducible.
#pragma once

#include <string>
#include <vector>

#include "core/options.h"

namespace hamal::aprilsam {

// Parsed once, when the back-end is made (fromOptions): the choices are
// enums, so no step compares option strings.
struct UpdatePolicyOptions {
  enum class Mode { kAdaptive, kPeriodic, kIncremental };  // option names: adaptive, ...
  enum class Cost { kDeterministic, kWallclock };          // deterministic, wallclock
  Mode mode = Mode::kAdaptive;       // Alg. 3.1 | a batch every `period` steps | first only
  long period = 10;                  // k: a batch every k steps in periodic mode
  double delta_t = 0.1;              // delta_T: |dx_i| (inf-norm) at which node i joins L
  long nl_t = 100;                   // NL_T: batch when |L| >= NL_T
  double big_delta_t = 10.0;         // Delta_T: batch when ||dx|| (2-norm) >= Delta_T
  Cost cost = Cost::kDeterministic;  // what the time criterion compares
};
// The option value that names each choice ("adaptive", "wallclock").
const char* toString(UpdatePolicyOptions::Mode mode);
const char* toString(UpdatePolicyOptions::Cost cost);

struct UpdateCosts {       // what the back-end measured/predicted for the last updates
  double incremental = 0;  // last incremental update: seconds or flops
  double batch = 0;        // last batch update, same unit
  long possible_loop_closure_nodes = 0;  // n_lc (COUNTPOSSIBLELOOPCLOSURENODES)
};

struct UpdateDecision {
  bool batch = false;
  std::string reason;  // the criterion met, with its numbers; why not, for an incremental step
};

class UpdatePolicy {
 public:
  explicit UpdatePolicy(UpdatePolicyOptions options);

  // Called after the incremental update of step `step` (0-based) with the
  // state changes it produced: `moved_nodes` = |L|, `dx_norm` = ||dx||.
  UpdateDecision decide(long step, long moved_nodes, double dx_norm,
                        const UpdateCosts& costs) const;

  const UpdatePolicyOptions& options() const { return options_; }

  // The registry options, with help giving the thesis symbol and default.
  static std::vector<OptionSpec> optionSpecs();
  // Reads and validates them; throws hamal::Error naming the bad option.
  static UpdatePolicyOptions fromOptions(const Options& o);

 private:
  UpdatePolicyOptions options_;
};

}  // namespace hamal::aprilsam
