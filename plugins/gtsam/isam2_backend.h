// Isam2Backend: GTSAM's iSAM2 (Kaess et al., "iSAM2: Incremental smoothing
// and mapping using the Bayes tree", IJRR 2012) as the hamal back-end
// "isam2", the incremental solver the thesis compares AprilSAM with (sec.
// 3.5, fig. 3.9: relinearisation threshold sweep; tables 3.2-3.4).
//
// One update() is one ISAM2::update() with the step's factors (mapped by
// gtsam_factor_adapter.h) and new variables, then the estimate
// ISAM2::calculateEstimate() gives, because the thesis protocol makes the next step from the
// current estimate (docs/PROTOCOL.md). The whole is the step's time, as for every back-end;
// UpdateResult::time splits it:
//   other    - converting the step to GTSAM's factors and values;
//   factor   - the ISAM2::update() call: GTSAM relinearises, orders and
//              eliminates inside it and does not report the split;
//   estimate - what calculateEstimate() computes (iSAM2's wildfire-limited
//              back-substitution, theta retracted by delta), written into
//              hamal's Values and checked for finiteness: O(variables) per
//              step, as calculateEstimate() is.
// seconds minus estimate is "update only", the figure GTSAM's own timings
// give; hamal_bench prints both.
//
// Counts are GTSAM's own (ISAM2Result): variables_relinearized is
// variablesRelinearized; columns_recomputed is variablesReeliminated times
// the variables' dimension (exact while every variable has one dimension,
// as in pose graphs; with landmarks it counts each re-eliminated variable as
// a pose); the reason line gives variablesReeliminated, factorsRecalculated
// and the Bayes tree's cliques.
//
// Options (GTSAM's ISAM2Params, defaults GTSAM's): relinearize_threshold,
// relinearize_skip, optimizer (gauss-newton or dogleg), wildfire_threshold.
//
// A GTSAM exception (an indeterminant system: an unanchored graph) is a
// numerical-failure Status naming the variable GTSAM names; a non-finite
// estimate is one too. Bad input throws hamal::Error before anything is
// recorded, as every back-end does (core/step.h).
#pragma once

#include <gtsam/nonlinear/ISAM2.h>

#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/registry.h"

namespace hamal::gtsam_plugin {

struct Isam2Options {
  double relinearize_threshold = 0.1;
  int relinearize_skip = 10;
  bool dogleg = false;
  double wildfire_threshold = 0.001;
};

class Isam2Backend : public Backend {
 public:
  explicit Isam2Backend(const Isam2Options& options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return estimate_; }

 private:
  Status refreshEstimate();

  gtsam::ISAM2 isam_;
  Values estimate_;
  std::vector<Key> fixed_;  // held by strong priors; estimate_ keeps their values
  std::unordered_set<Key> fixed_set_;
  std::size_t columns_total_ = 0;
  bool uniform_dimension_ = true;  // every variable has the first one's dimension
  int dimension_ = 0;
};

// The registry entry "isam2".
BackendInfo isam2Info();

}  // namespace hamal::gtsam_plugin
