// LinearizedGraph: the graph G of Alg. 3.1 as AprilSAM holds it (thesis
// sec. 3.3-3.4): each variable with its linearisation point (mu of eq. 3.3)
// and its estimate lin_point [+] dx, each factor with the weight and mode R
// holds it with, and the Gauss-Newton system for dx at those points: A_new
// and b_new as they are assembled (eq. 3.5-3.7, BlockNormalEquations, or
// Jacobian rows for a rank update), R and y (IncrementalCholesky), dx
// (PartialBacksolve). AugmentGraph (line 2) adds to it; the batch update,
// the top re-elimination and the component-switch hook change it.
//
// Fixed variables (Step::fixed) have no position in the order and no column
// in R; their Jacobian blocks are dropped and their values stay in the
// residuals. A factor's weight (core/factor_weights.h) scales its rows by
// sqrt(w); R holds each factor at the weight it had when it was linearised.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <unordered_map>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/incremental_cholesky.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/mode_tracking.h"
#include "backends/aprilsam/partial_backsolve.h"
#include "core/backend.h"
#include "core/factor.h"
#include "core/linearization.h"
#include "core/values.h"

namespace hamal::aprilsam {

struct LinearizedGraph {
  LinearizedGraph(double dormant_scale, double delta_t) : modes(dormant_scale), delta_t(delta_t) {
    factor_begin.push_back(0);
  }
  LinearizedGraph(const LinearizedGraph&) = delete;  // est points into estimate
  LinearizedGraph& operator=(const LinearizedGraph&) = delete;

  // AugmentGraph: a new variable at the end of the order (no position when
  // fixed), at its initial guess; its index v.
  int addVariable(Key key, const Values::Entry& guess, bool fixed);
  // AugmentGraph: a new factor on known variables at weight 1; its index f.
  int addFactor(const FactorPtr& factor);

  // Linearises factors [begin, end) at the linearisation points into neq,
  // or as rows into rows when `as_rows`; false with the status set when one
  // or their sum is not finite.
  bool linearizeFactors(std::size_t begin, std::size_t end, bool as_rows, UpdateResult* result);
  // One factor, sign x its contribution (-1 takes an old one out again) at
  // the weight and mode R holds it with. A dormant factor contributes
  // nothing, either way.
  bool linearizeFactor(std::size_t f, double sign, bool as_rows, UpdateResult* result);
  // Factor f's parameters (at the linearisation points, or the estimate),
  // positions and dimensions into params, fpos, fdims; true when it touches
  // a fixed variable.
  bool gatherFactor(std::size_t f, bool at_lin_point);
  // `factor` (f or one of its mode components) linearised at params into
  // scratch, the blocks of fixed variables dropped.
  bool linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                         UpdateResult* result);
  // The reweighted factors' differences into neq (FactorWeights).
  bool reweighFactors(UpdateResult* result);
  // Factor f's parameters at the estimate into params (for Factor::mode).
  void gatherEstimate(std::size_t f);

  // UPDATELINEARIZATIONPOINT (Alg. 3.1 line 12) of variable v.
  void moveLinearizationPoint(int v) {
    for (int t = 0; t < dims[v]; ++t) lin[v].data[t] = est[v][t];
  }
  // estimate = lin_point [+] dx for the variables whose dx changed (Alg. 3.1
  // lines 5-8), and the bookkeeping of L and ||dx|| that the update policy
  // reads.
  void applyChangedDx();
  // After applyChangedDx: a non-ok status in `result` when a changed
  // variable's estimate is not finite.
  bool estimateIsFinite(UpdateResult* result);
  // Variable v's place for the orderings' input (eq. 3.20's distance): its
  // linearisation point, far away when not finite.
  Eigen::Vector2d orderingPosition(int v) const;

  // Per variable (index v in order of arrival).
  std::vector<Key> keys;
  std::vector<int> dims;
  std::vector<char> fixed;  // held at its value, no position (core/step.h)
  std::vector<Values::Entry> lin;
  std::vector<double*> est;      // into estimate (stable: unordered_map nodes)
  std::vector<int> pos_of;       // v -> position in the elimination order, -1 if fixed
  std::vector<char> moved;       // v in L (|dx_v|_inf >= delta_T)
  std::vector<double> dx_sq_of;  // |dx_v|^2
  std::unordered_map<Key, int> index;
  std::vector<int> var_at;  // position -> v
  int newest_pose = -1;
  Values estimate;

  std::vector<FactorPtr> factors;
  // Per factor: its weight, the weight R holds it with, and the factors
  // whose two differ; the factors by address.
  std::vector<double> weight, lin_weight;
  std::vector<int> reweighted;
  std::unordered_map<const Factor*, int> factor_index;
  std::vector<int> factor_vars;   // flat: the variables of each factor
  std::vector<int> factor_begin;  // factors.size() + 1 offsets into it
  std::vector<std::vector<int>> factors_of_var;
  ModeTracking modes;
  // Visit stamps of the passes over factors and variables.
  std::vector<long> factor_stamp, var_stamp;
  long stamp = 0;

  BlockNormalEquations neq;
  JacobianRows rows;
  IncrementalCholesky chol;
  PartialBacksolve solve;
  Linearization scratch;
  std::vector<const double*> params;
  std::vector<int> fpos, fdims;

  double delta_t;                  // delta_T: a variable whose |dx|_inf reaches it is in L
  long moved_count = 0;            // |L|
  double dx_sq = 0;                // ||dx||^2, kept as dx changes
  bool broken = false;             // the last batch failed: R is not usable, batch again
  bool damped = false;             // R holds the damping of a damped batch
  std::size_t factors_at_top = 0;  // factors.size() at the last batch or top re-elimination
  double last_batch_cost = 0;      // what the time criterion weighs increments against
  std::vector<Key> changed_keys;   // scratch of estimateIsFinite
};

}  // namespace hamal::aprilsam
