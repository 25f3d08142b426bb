// LinearizedGraph: the graph G of Alg. 3.1 as AprilSAM holds it (thesis
// sec. 3.3-3.4), the owner of its parts, each keeping its own invariants:
//   - VariableTable: each variable with its linearisation point (mu of eq.
//     3.3) and its estimate lin_point [+] dx;
//   - EliminationOrder: each free variable's position (row of R);
//   - RelinearizationSet: L and ||dx||, kept as dx changes;
//   - FactorTable: each factor with its variables and its weights;
//   - ModeTracking: the mode R holds each factor with modes in;
//   - the Gauss-Newton system for dx at the linearisation points: A_new and
//     b_new as they are assembled (eq. 3.5-3.7, BlockNormalEquations, or
//     Jacobian rows for a rank update), R and y (IncrementalCholesky), dx
//     (PartialBacksolve);
//   - BatchRecord: what the last batch left (failed, damped, its cost).
// It keeps the parts in step where one change touches several: a new
// variable (AugmentGraph, Alg. 3.1 line 2) gets a position, a column of R
// and a dx; a reordering moves the order and dx together; a solve's dx
// moves the estimate and L. The batch update, the top re-elimination and
// the component-switch hook change it through these.
//
// Fixed variables (Step::fixed) have no position in the order and no column
// in R; their Jacobian blocks are dropped and their values stay in the
// residuals. A factor's weight (core/factor_weights.h) scales its rows by
// sqrt(w); R holds each factor at the weight it had when it was linearised.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/elimination_order.h"
#include "backends/aprilsam/factor_table.h"
#include "backends/aprilsam/incremental_cholesky.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/mode_tracking.h"
#include "backends/aprilsam/partial_backsolve.h"
#include "backends/aprilsam/relinearization_set.h"
#include "backends/aprilsam/variable_table.h"
#include "core/backend.h"
#include "core/factor.h"
#include "core/linearization.h"
#include "core/values.h"

namespace hamal::aprilsam {

// What the last batch (or top re-elimination) left R as, and what the
// update policy's time criterion weighs increments against.
struct BatchRecord {
  bool broken = false;             // the last batch failed: R is not usable, batch again
  bool damped = false;             // R holds the damping of a damped batch
  std::size_t factors_at_top = 0;  // factors at the last batch or top re-elimination
  double last_batch_cost = 0;      // its cost (seconds or flops, UpdatePolicyOptions::Cost)
};

class LinearizedGraph {
 public:
  LinearizedGraph(double dormant_scale, double delta_t) : moved_(delta_t), modes_(dormant_scale) {}
  LinearizedGraph(const LinearizedGraph&) = delete;
  LinearizedGraph& operator=(const LinearizedGraph&) = delete;

  // AugmentGraph: a new variable at the end of the order (no position when
  // fixed), at its initial guess; its index v.
  int addVariable(Key key, const Values::Entry& guess, bool fixed);
  // AugmentGraph: a new factor on known variables at weight 1; its index f.
  int addFactor(const FactorPtr& factor);

  const VariableTable& variables() const { return vars_; }
  VariableTable& variables() { return vars_; }
  const EliminationOrder& order() const { return order_; }
  const RelinearizationSet& moved() const { return moved_; }
  const FactorTable& factors() const { return factors_; }
  FactorTable& factors() { return factors_; }
  const ModeTracking& modes() const { return modes_; }
  ModeTracking& modes() { return modes_; }
  BlockNormalEquations& neq() { return neq_; }
  JacobianRows& rows() { return rows_; }
  const IncrementalCholesky& chol() const { return chol_; }
  IncrementalCholesky& chol() { return chol_; }
  const PartialBacksolve& solve() const { return solve_; }
  PartialBacksolve& solve() { return solve_; }
  const BatchRecord& record() const { return record_; }
  BatchRecord& record() { return record_; }

  // A batch's order of the free variables (`order`, first eliminated
  // first); their dimensions in that order. R and dx are the caller's to
  // reset to them.
  std::vector<int> layOutOrder(const std::vector<int>& order);
  // The top re-elimination's new positions (IncrementalCholesky::
  // reorderTop): position p's variable and dx move to new_pos[p].
  void permuteOrder(const std::vector<int>& new_pos) {
    order_.permute(new_pos);
    solve_.permute(new_pos);
  }

  // Linearises factors [begin, end) at the linearisation points into neq,
  // or as rows into rows when `as_rows`; false with the status set when one
  // or their sum is not finite.
  bool linearizeFactors(std::size_t begin, std::size_t end, bool as_rows, UpdateResult* result);
  // One factor, sign x its contribution (-1 takes an old one out again) at
  // the weight and mode R holds it with. A dormant factor contributes
  // nothing, either way.
  bool linearizeFactor(std::size_t f, double sign, bool as_rows, UpdateResult* result) {
    return linearizeFactorAt(f, sign, as_rows, order_.positions(), result);
  }
  // linearizeFactor with the variables at `positions` (v -> column block,
  // -1: none, its block dropped) instead of the order's.
  bool linearizeFactorAt(std::size_t f, double sign, bool as_rows, const int* positions,
                         UpdateResult* result);
  // The cost (chi2 at the weight) of the last factor linearised.
  double lastCost() const { return scratch_.cost; }
  // The reweighted factors' differences into neq (FactorWeights).
  bool reweighFactors(UpdateResult* result);
  // `component` of factor f, linearised at f's linearisation point, times
  // w into neq (or as rows times sqrt(w)), at f's weight in neither.
  bool addComponent(std::size_t f, const Factor& component, double w, bool as_rows,
                    UpdateResult* result);
  // Factor f's mode (MultiModal::mode) at the estimate, or at the linearisation
  // points.
  int modeAtEstimate(std::size_t f);
  int modeAtLinearizationPoint(std::size_t f);

  // estimate = lin_point [+] dx for the variables whose dx changed (Alg. 3.1
  // lines 5-8), and the bookkeeping of L and ||dx|| that the update policy
  // reads.
  void applyChangedDx();
  // A batch's dx: L and ||dx|| from nothing, then applyChangedDx.
  void applyBatchDx() {
    moved_.clear();
    applyChangedDx();
  }
  // After applyChangedDx: a non-ok status in `result` when a changed
  // variable's estimate is not finite.
  bool estimateIsFinite(UpdateResult* result);
  // The changed variables' estimates back at their linearisation points.
  void resetChangedEstimates();

 private:
  // Factor f's parameters at the linearisation points, positions (from
  // `positions`) and dimensions into params_, fpos_, fdims_; true when it
  // touches a variable with no position.
  bool gatherFactor(std::size_t f, const int* positions);
  // `factor` (f or one of its mode components) linearised at params_ into
  // scratch_, the blocks of variables with no position dropped.
  bool linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                         UpdateResult* result);

  VariableTable vars_;
  EliminationOrder order_;
  RelinearizationSet moved_;
  FactorTable factors_;
  ModeTracking modes_;
  BlockNormalEquations neq_;
  JacobianRows rows_;
  IncrementalCholesky chol_;
  PartialBacksolve solve_;
  BatchRecord record_;
  // Scratch of the linearisation, and of estimateIsFinite.
  Linearization scratch_;
  std::vector<const double*> params_;
  std::vector<int> fpos_, fdims_;
  std::vector<Key> changed_keys_;
};

}  // namespace hamal::aprilsam
