// AprilSamBackend: the AprilSAM algorithm (thesis ch. 3, Alg. 3.1) put
// together from its named parts:
//   - BlockNormalEquations: A_new, b_new of the step's factors (eq. 3.5-3.7);
//   - IncrementalCholesky: R and y updated on the affected rows (eq. 3.14,
//     3.19, figs. 3.5-3.6);
//   - PartialBacksolve: dx from R dx = y, partial or full (fig. 3.7);
//   - UpdatePolicy: incremental or batch (sec. 3.4.4);
//   - minHeapOrdering / bhamdOrdering / amdOrdering for batches (sec. 3.4.3).
//
// State: each variable has a linearisation point; the factor R and y describe
// the Gauss-Newton system for dx relative to it (new factors are linearised
// at the current linearisation point of their variables, new variables at
// their initial guess), and the estimate is lin_point [+] dx. New variables
// are appended at the end of the order between batches. A batch (Alg. 3.1
// lines 12-16) moves every linearisation point to the estimate, reorders,
// refactors and solves: ONE Gauss-Newton step as in the thesis and its
// reference code; batch_iterations > 1 repeats it.
//
// Fixed variables (Step::fixed) have no position in the order and no column
// in R; their Jacobian blocks are dropped and their values stay in the
// residuals. Fixing a variable that already has a column runs a batch.
//
// Dormant factors: a factor with modes whose mode at its linearisation point
// carries an information scale below dormant_scale (a max-mixture's null
// hypothesis, Factor::modeInformationScale) contributes no rows to R, no
// entry to the orderings' graph and no fill: it is out of the system while
// that mode is active. The approximation: the dropped term's gradient and
// Hessian are scale x the nominal's (1e-12 x for the usual null hypothesis),
// so the estimate moves by that fraction of what the nominal factor would
// pull. When the switch hook finds it active at the estimate it enters the
// system as its variables are relinearised (its rows added like a new
// factor's); switching off again subtracts its rows the same way. Its row
// structure then stays in R until the next batch, which leaves it out.
//
// Numerical failure: when an incremental update meets a diagonal block that
// is not positive definite, the step falls back to a batch with
// Levenberg-style damping (A_ii += lambda diag(A_ii)), and says so in the
// reason; when that fails too the Status names the variable. Nothing aborts.
#pragma once

#include <array>
#include <string>
#include <unordered_map>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/incremental_cholesky.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/aprilsam/ordering_input.h"
#include "backends/aprilsam/partial_backsolve.h"
#include "backends/aprilsam/update_policy.h"
#include "core/backend.h"
#include "core/factor_weights.h"
#include "core/options.h"

namespace hamal::aprilsam {

// Parsed once, when the back-end is made (fromOptions): the choices are
// enums, so no step compares option strings.
struct AprilSamOptions {
  enum class Ordering { kMinHeap, kBhamd, kAmd, kNatural };  // minheap, bhamd, amd, natural
  enum class FactorUpdate { kRank, kRefactor };              // rank, refactor
  enum class Backsolve { kPartial, kFull };                  // partial, full
  enum class Reeliminate { kFull, kTop };                    // full, top

  UpdatePolicyOptions policy;
  Ordering ordering = Ordering::kMinHeap;
  double loop_closure_radius = 5.0;                  // R_T (eq. 3.20 and n_lc), metres
  long n_lc = 3;                                     // fixed n_lc; 0: count the nodes within R_T
  FactorUpdate factor_update = FactorUpdate::kRank;  // addRows | eq. 3.14
  long rank_update_max_rows = 64;                    // more new rows than this: refactor
  Backsolve backsolve = Backsolve::kPartial;         // full: AprilSAM-FullSolve
  double backsolve_tol = 1e-3;                       // propagate dx changes larger than this
  long batch_iterations = 1;                         // Gauss-Newton steps per batch update
  bool batch_first = false;     // cost and periodic criteria before the incremental update
  double damping = 1e-4;        // lambda of the damped fallback batch
  double dormant_scale = 1e-5;  // a mode carrying less information than this: no rows
  Reeliminate reeliminate = Reeliminate::kFull;  // what a batch decision re-eliminates
  double top_share = 0.5;        // reeliminate=top: a larger top (share of R's rows) batches
  double top_relinearize = 0.3;  // reeliminate=top: relinearise |dx_i| >= this x delta_T too

  static std::vector<OptionSpec> optionSpecs();
  // Throws hamal::Error naming a bad option.
  static AprilSamOptions fromOptions(const Options& options);
};

class AprilSamBackend : public Backend, public FactorWeights {
 public:
  explicit AprilSamBackend(AprilSamOptions options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return estimate_; }

  // Factor weights (core/factor_weights.h): R holds each factor at the
  // weight it had when it was linearised; the next update takes the
  // difference out and in at the factor's linearisation point, in the same
  // refactorisation of the affected rows as the step's new factors (a
  // reweighted factor is a change of H like a relinearised one), so only
  // the rows below the factor's variables are refactored. Weight 0 leaves
  // the factor's rows out; its place in the ordering stays until a batch.
  void setFactorWeight(const Factor* factor, double weight) override;
  double factorWeight(const Factor* factor) const override;
  // G from R: Z = R^-T J^T by forward substitution over the elimination-tree
  // paths from the factors' variables to the root (the rows an update of
  // those factors would refactor), G = Z^T Z. False after a failed or
  // damped batch (R is not the undamped system) or for a factor on a
  // variable it does not hold (the factor itself need not be held).
  bool residualCovariance(const std::vector<const Factor*>& factors, Eigen::MatrixXd* g) override;

  // For tests: the factor and its order (position of a variable, the
  // variable at a position), and each variable's linearisation point.
  const IncrementalCholesky& factor() const { return chol_; }
  const PartialBacksolve& backsolve() const { return solve_; }
  int positionOf(Key key) const { return pos_of_[index_.at(key)]; }  // -1: fixed
  Key keyAt(int position) const { return keys_[var_at_[position]]; }
  const Values::Entry& linearizationPoint(Key key) const { return lin_[index_.at(key)]; }
  const std::vector<FactorPtr>& factors() const { return factors_; }
  int batches() const { return batches_; }
  // Factors with modes that the last batch left out as dormant.
  long dormantFactors() const { return dormant_count_; }

 private:
  // Linearises factors [begin, end) at the linearisation points into neq_,
  // or as rows into rows_ when `as_rows`.
  bool linearizeFactors(std::size_t begin, std::size_t end, bool as_rows, UpdateResult* result);
  // One factor, sign x its contribution (-1 takes an old one out again).
  // A dormant factor (see above) contributes nothing, either way.
  bool linearizeFactor(std::size_t f, double sign, bool as_rows, UpdateResult* result);
  // Factor f's parameters (at the linearisation points, or the estimate),
  // positions and dimensions into params_, fpos_, fdims_; true when it
  // touches a fixed variable.
  bool gatherFactor(std::size_t f, bool at_lin_point);
  // `factor` (f or one of its components) linearised at params_ into
  // lin_scratch_, the blocks of fixed variables dropped.
  bool linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                         UpdateResult* result);
  // lin_scratch_ times a factor weight w: rows and residual by sqrt(w).
  void scaleScratch(double w);
  // The reweighted factors' differences into neq_ (setFactorWeight).
  bool reweighFactors(UpdateResult* result);
  // A nominal + null pair's nominal component.
  const Factor* nominalComponent(std::size_t f) const;
  // A raised switch (see relinearizeSwitchedModes): the nominal component
  // of null pair f, which R holds in its null mode, added at f's
  // linearisation point as rows or into neq_.
  bool raiseToNominal(std::size_t f, bool as_rows, UpdateResult* result);
  // The component-switch hook (Factor::mode): a factor whose mode at the
  // estimate differs from the one R holds it linearised with has its
  // variables relinearised at the estimate, and every factor on them: the
  // old contributions out, the new ones in, the affected rows of R
  // refactored (as GTSAM's extraReelimKeys). Repeats while switches appear,
  // a few passes at most. A pass whose switches are all raised (a nominal +
  // null pair whose null mode R holds turning nominal, the usual switch of
  // a new measurement whose first guess put it outside the gate) adds the
  // nominal's missing share at the linearisation point instead, as rows of
  // a rank update: exact for the model linearised there, as a new factor is.
  void relinearizeSwitchedModes(UpdateResult* result);
  bool solveAfterSwitch(const IncrementalCholesky::Outcome& out, UpdateResult* result);
  // What the update policy weighs: this incremental cost against the last
  // batch's, and the possible loop-closure nodes.
  UpdateCosts updateCosts(double incremental) const;
  void applyChangedDx();
  // Alg. 3.1 lines 12-16; `reason` says why.
  void batchUpdate(const std::string& reason, bool damped, UpdateResult* result);
  // reeliminate=top: instead of a batch, iSAM2's re-elimination of the top
  // of the factor (IncrementalCholesky::topOf, reorderTop): the rows that
  // the factors added since the last re-elimination and the variables in L
  // (and those within top_relinearize of it) reach, reordered by minheap
  // and refactored; the variables in the top that no factor ties to a kept
  // row move their linearisation points to the estimate. False, with nothing changed that a batch
  // does not redo, when it does not apply (factors with modes, a damped factor, a top of more than
  // top_share of the rows, a top that is not positive definite): the caller batches.
  bool reeliminateTop(const std::string& reason, UpdateResult* result);
  // A batch decision carried out: the top re-eliminated where
  // reeliminate=top and reeliminateTop applies, else a batch and the mode
  // switches after it.
  void batchOrTop(const std::string& reason, UpdateResult* result);
  std::vector<int> computeOrdering();
  // True when factor f, at mode m, is left out of the system (dormant_scale).
  bool dormant(std::size_t f, int m) const;
  long countPossibleLoopClosureNodes() const;
  void gridInsert(int v);
  long gridCell(double x, double y) const;
  // After applyChangedDx: a non-ok status in `result` when a changed
  // variable's estimate is not finite.
  bool estimateIsFinite(UpdateResult* result);
  Eigen::Vector2d location(int v) const;
  // location(v) for the orderings' input: far away when not finite.
  Eigen::Vector2d orderingPosition(int v) const;

  AprilSamOptions options_;
  UpdatePolicy policy_;

  // Per variable (index v in order of arrival).
  std::vector<Key> keys_;
  std::vector<int> dims_;
  std::vector<char> fixed_;  // held at its value, no position (core/step.h)
  std::vector<Values::Entry> lin_;
  std::vector<double*> est_;      // into estimate_ (stable: unordered_map nodes)
  std::vector<int> pos_of_;       // v -> position in the elimination order, -1 if fixed
  std::vector<char> moved_;       // v in L (|dx_v|_inf >= delta_T)
  std::vector<double> dx_sq_of_;  // |dx_v|^2
  std::unordered_map<Key, int> index_;
  std::vector<int> var_at_;  // position -> v
  int newest_pose_ = -1;

  std::vector<FactorPtr> factors_;
  // Per factor: its weight, the weight R holds it with, and the factors
  // whose two differ (FactorWeights); the factors by address.
  std::vector<double> weight_, lin_weight_;
  std::vector<int> reweighted_;
  std::unordered_map<const Factor*, int> factor_index_;
  std::vector<int> factor_vars_;   // flat: the variables of each factor
  std::vector<int> factor_begin_;  // factors_.size() + 1 offsets into it
  // For the component-switch hook: the factors on each variable (all, and
  // those with modes), the mode each factor is linearised with, and visit
  // stamps.
  std::vector<std::vector<int>> factors_of_var_, moded_of_var_;
  std::vector<int> lin_mode_;
  // Per factor: a nominal + null pair (MaxMixtureFactor::isNullHypothesisPair),
  // and whether R holds its nominal component at a linearisation point where
  // its null mode is active (after a raised switch; until it is relinearised).
  std::vector<char> null_pair_, held_nominal_;
  // Set by computeOrdering, which has just written lin_mode_ for every
  // factor with modes at the batch's linearisation points, until the
  // batch has linearised them.
  bool modes_at_lin_known_ = false;
  std::vector<long> factor_stamp_, var_stamp_;
  long stamp_ = 0;
  bool any_modes_ = false;
  // The factors with modes are kept out of ordering_input_: each batch adds
  // the edges of those not dormant at the new linearisation points to a copy.
  std::vector<int> moded_factors_;
  OrderingInput moded_ordering_input_;
  long dormant_count_ = 0;  // factors left out at the last batch

  Values estimate_;
  BlockNormalEquations neq_;
  JacobianRows rows_;
  IncrementalCholesky chol_;
  PartialBacksolve solve_;
  Linearization lin_scratch_;
  std::vector<const double*> params_;
  std::vector<int> fpos_, fdims_;

  long moved_count_ = 0;  // |L|
  double dx_sq_ = 0;      // ||dx||^2, kept as dx changes
  long steps_ = 0;
  int batches_ = 0;
  bool broken_ = false;  // the last batch failed: R is not usable, batch again
  double last_batch_cost_ = 0;
  bool damped_ = false;             // R holds the damping of a damped batch
  std::size_t factors_at_top_ = 0;  // factors_.size() at the last batch or top re-elimination
  std::unordered_map<long, std::vector<int>> grid_;  // cell -> variables
  std::vector<Key> changed_keys_;                    // scratch of estimateIsFinite
  // The variable graph for the batch orderings, grown with each factor so a
  // batch does not rebuild it (positions are refreshed at each batch).
  OrderingInput ordering_input_;
  // The min-heap ordering's lists, reused by every batch and top.
  OrderingWorkspace ordering_workspace_;
};

}  // namespace hamal::aprilsam
