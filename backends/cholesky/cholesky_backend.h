// CholeskyBackend: sqrt-SAM-Chol, the batch baseline of thesis sec. 3.5.1:
// at every update the whole problem is relinearised and solved to
// convergence by Gauss-Newton on the normal equations
//     (J^T J) dx = -J^T r0        (thesis eq. 3.6-3.8)
// with a sparse Cholesky factorisation from CHOLMOD.
//
// Why it is fast enough to run at every step of a 10000-pose benchmark:
//  - H = J^T J lives in one preallocated CSC matrix (upper triangle, one dense
//    block per pair of variables that share a factor). Each factor knows, for
//    each pair of its variables, where its block sits, so assembling H is a
//    sweep of dense block additions: no triplets, no sorting.
//  - The pattern and CHOLMOD's symbolic analysis (the fill-reducing ordering)
//    are redone only when a step adds variables or factors or a factor goes
//    dormant or wakes up (below); the Gauss-Newton iterations of one update
//    otherwise refactor numerically only.
//  - The factorisation is simplicial by default: on these 2D graphs the
//    supernodes are small and the supernodal path's dense BLAS calls (ATLAS on
//    Debian) cost more than they save (figures: docs/RECORD.md).
//    Option factorization=supernodal|auto restores CHOLMOD's other paths.
//  - Each iteration linearises once: the linearisation at the candidate both
//    decides whether the step is accepted and is the next iteration's system.
//
// Convergence (each is an option): an update stops when the decrease the
// quadratic model predicts for the next step is below function_tolerance x cost
// (that tiny step is still applied when it is a pure Gauss-Newton step), when
// an accepted step lowered the cost by less than function_tolerance x cost, or when
// |dx| <= parameter_tolerance (|x| + parameter_tolerance). max_iterations linear solves
// without that -> Status kNotConverged.
//
// Safeguard: a Gauss-Newton step that increases the cost is rejected and the
// solve falls back to Levenberg-Marquardt, (H + lambda diag(H)) dx = -g with
// lambda growing x10 from lambda_initial until the cost decreases (and
// shrinking x10 after each accepted step, back to pure Gauss-Newton below
// 1e-9), so that it converges from odometry on M3500, intel, city10000 and
// manhattan. diag(H) is clamped to >= 1e-6 as Ceres does.
//
// Fixed variables (Step::fixed) have no column in H (a width of 0); fixing
// a known variable lays the columns out again. Which variable owns which
// columns is hamal's VariableLayout (core/variable_layout.h), shared with the
// other back-ends; the estimate and the candidate are two Values, so the
// rest of BackendKit (core/backend_kit.h) is not used.
//
// Dormant factors (option dormant_scale, core/dormant_policy.h, the rule
// AprilSAM reads too): a factor with modes whose mode at the current
// estimate is dormant (a max-mixture's null hypothesis) adds nothing to H or g and has no block in
// H's pattern, so a false loop closure switched off brings no fill. Its cost
// still counts: the cost that accepts steps and stops the iterations is the
// whole objective. The dropped gradient and Hessian are scale x the
// nominal's (1e-12 x for the usual null hypothesis). A factor's dormancy is
// read when it arrives, at every accepted step and at the estimate an update
// returns; when the dormant set changes, the blocks, the pattern and the
// symbolic analysis are redone (as when a step adds factors), otherwise the
// iterations refactor numerically only. A variable whose only factors are
// dormant has no information: the numerical failure below, whose message
// says so and suggests dormant_scale=0.
//
// A system that is not positive definite (a variable nothing constrains in
// some direction) is a Status kNumericalFailure naming the variable of the
// column where CHOLMOD's factorisation stopped, or, since rounding often
// leaves a tiny positive pivot instead, of the column whose pivot L_jj^2 is
// below singular_tolerance x H_jj. The update stops there with the estimate
// of its last accepted step, and later updates go on.
//
// Marginal covariances (core/marginals.h): H is assembled and factorised
// again at the estimate (the factor the update left may be damped or of the
// candidate), and the columns of H^-1 for the asked variables' scalar
// columns are solved for with unit vectors on that factor: k solves for k
// scalar columns, never the whole inverse. Refused (a Status) when the last
// update did not end ok.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <unordered_map>
#include <vector>

#include "backends/cholesky/cholmod_handles.h"
#include "core/backend.h"
#include "core/dormant_policy.h"
#include "core/linearization.h"
#include "core/marginals.h"
#include "core/multi_modal.h"
#include "core/options.h"
#include "core/registry.h"
#include "core/variable_layout.h"

namespace hamal {

class CholeskyBackend : public Backend, public MarginalCovariances {
 public:
  static std::vector<OptionSpec> optionSpecs();
  // Throws hamal::Error on an option value that does not parse.
  explicit CholeskyBackend(const Options& options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return values_[current_]; }
  // The covariance at the estimate (see above).
  Status jointMarginalCovariance(const std::vector<Key>& keys,
                                 Eigen::MatrixXd* covariance) override;

  // For tests: the factors left out of H as dormant, and the entries of H's
  // pattern (upper triangle), both as the last update left them.
  long dormantFactors() const { return dormant_count_; }
  long patternNonzeros() const;

 private:
  // Variable i of layout_ (its columns in H are layout_'s).
  struct Variable {
    int size = 0;  // parameters in Values
    // The blocks of H's block column of this variable: (row variable, block),
    // sorted by row variable, ending with the diagonal block.
    std::vector<std::pair<int, int>> blocks;
    double* data[2] = {nullptr, nullptr};  // in values_[0] and values_[1]
  };
  struct Block {
    int row_var = 0, col_var = 0;  // row_var <= col_var
    long offset = 0;               // row position of the block inside each of its columns
  };
  struct FactorSlot {
    FactorPtr factor;
    const MultiModal* modes = nullptr;  // the factor's modes (asMultiModal), if any
    std::vector<int> vars;              // variable index of each key
    std::vector<int> blocks;  // block of each key pair (a <= b), row-major; none when dormant
    bool dormant = false;     // left out of H and its pattern (dormant_scale)
  };

  UpdateResult solve(const Step& step);
  void addStep(const Step& step);
  // Every block column's offsets again, after a known variable was fixed.
  void relayout();
  int blockFor(int i, int j);
  void addFactorBlocks(FactorSlot* slot);
  // Blocks of every variable's diagonal and of every factor that is not
  // dormant, from scratch: a factor that goes dormant takes its blocks away.
  void relayoutBlocks();
  // Whether factor `slot`'s mode at values_[which] is dormant (dormant_).
  bool dormantAt(const FactorSlot& slot, int which);
  // Sets every factor's dormant flag from its mode at values_[which] and
  // relays the blocks out when one changed.
  void syncDormant(int which);
  // Why variable `key` has a direction nothing constrains: "nothing
  // constrains it", and the dormant factors on it when it has some.
  std::string unconstrained(Key key) const;
  void rebuildPattern();
  // Fills scalar_permutation_ from an ordering of the variables; false when
  // CHOLMOD fails (out of memory).
  bool orderBlocks();
  // Assembles H (upper triangle, into h) and g = J^T r at values_[which]
  // from the factors that are not dormant, and the cost of every factor;
  // *switched tells whether a factor's dormancy at values_[which] differs
  // from its flag. Returns the index of a factor that cannot be evaluated,
  // or -1.
  long assemble(int which, std::vector<double>* h, Eigen::VectorXd* g, double* cost,
                bool* switched);
  // Factorises h + lambda diag(h); false (with *status set) when it fails.
  bool factorize(const std::vector<double>& h, double lambda, Status* status);
  // Why a factorisation failed when the cause is one factor's information
  // far above the others' (ill-conditioning, not a missing constraint): a
  // sentence naming that factor, or "" when the factors' scales are alike.
  std::string illConditioning();
  // min over columns of L_jj^2 / H_jj for the last factorisation, and the
  // column of H where it is.
  double weakestPivot(long* weakest_column) const;

  // Options.
  int max_iterations_;
  double rel_tolerance_, dx_tolerance_, lambda_initial_, singular_tolerance_;
  DormantPolicy dormant_;  // dormant_scale
  enum BlockOrdering { kScalar, kBlockAmd, kBlockColamd };
  BlockOrdering block_ordering_;

  Values values_[2];  // the estimate and the candidate, swapped on acceptance
  int current_ = 0;
  Status last_status_;  // of the last update that got past checkStep
  VariableLayout layout_;
  std::vector<Variable> variables_;  // in layout_ order
  std::vector<FactorSlot> factors_;
  std::vector<std::size_t> moded_;  // factors with modes (core/multi_modal.h)
  long dormant_count_ = 0;
  std::vector<Block> blocks_;
  std::unordered_map<std::uint64_t, int> block_index_;  // (i, j) -> block
  std::vector<int> dirty_columns_;                      // variables whose block column changed
  bool pattern_dirty_ = false;

  std::vector<SuiteSparse_long> block_permutation_, scalar_permutation_;
  std::vector<long> diagonal_;  // position of each scalar diagonal entry of H
  std::vector<double> h_[2];    // H's values at values_[0] / values_[1]
  Eigen::VectorXd g_[2];
  Linearization linearization_;
  std::vector<const double*> parameters_;

  cholesky::Common common_;
  cholesky::Sparse matrix_;  // H's pattern; values copied in before each factorisation
  cholesky::Factor factor_;
  cholesky::Dense rhs_, solution_, work_y_, work_e_;
};

}  // namespace hamal
