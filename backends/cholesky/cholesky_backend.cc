// CholeskyBackend: see cholesky_backend.h (thesis sec. 3.5.1, sqrt-SAM-Chol).
#include "backends/cholesky/cholesky_backend.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/finite_result.h"
#include "core/phase_clock.h"

namespace hamal {

namespace {

constexpr double kMinDiagonal = 1e-6;  // LM damping floor, as Ceres' min_lm_diagonal
constexpr double kMinLambda = 1e-9;    // below this, back to pure Gauss-Newton
constexpr double kMaxLambda = 1e10;    // above this no step can lower the cost

std::string keyList(const std::vector<Key>& keys) {
  std::string out;
  for (Key k : keys) out += (out.empty() ? "" : ", ") + k.str();
  return out;
}

std::string scientific(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

std::vector<OptionSpec> CholeskyBackend::optionSpecs() {
  return {
      {"max_iterations", "20", "linear solves per update before giving up (kNotConverged)"},
      {"function_tolerance",
       "1e-6",
       "stop when a step's predicted or actual cost decrease is below this fraction of the cost "
       "(old name: rel_tolerance)",
       {"rel_tolerance"}},
      {"parameter_tolerance",
       "1e-8",
       "stop when |dx| <= parameter_tolerance (|x| + parameter_tolerance) (old name: "
       "dx_tolerance)",
       {"dx_tolerance"}},
      {"lambda_initial", "1e-4",
       "Levenberg-Marquardt damping used after the first Gauss-Newton step that raises the cost"},
      {"singular_tolerance", "1e-10",
       "numerical failure when a pivot L_jj^2 of the factorisation is below this fraction of "
       "H_jj (the column is numerically dependent on the earlier ones)"},
      {"factorization", "simplicial",
       "CHOLMOD factorisation: simplicial (LDL^T, column by column) | supernodal (dense BLAS "
       "blocks) | auto (CHOLMOD picks by flops per nonzero). The rows of a 2D graph are short, "
       "which suits simplicial"},
      {"ordering", "block_amd",
       "fill-reducing ordering: block_amd | block_colamd (AMD on H's, COLAMD on J's "
       "variable graph, as Ceres and sqrt-SAM) | amd | metis | natural (CHOLMOD on scalar H)"},
      DormantPolicy::optionSpec(),
  };
}

CholeskyBackend::CholeskyBackend(const Options& options) {
  max_iterations_ = static_cast<int>(options.getInt("max_iterations"));
  if (max_iterations_ < 1) throw Error("cholesky: option max_iterations must be >= 1");
  rel_tolerance_ = options.getDouble("function_tolerance");
  singular_tolerance_ = options.getDouble("singular_tolerance");
  dx_tolerance_ = options.getDouble("parameter_tolerance");
  lambda_initial_ = options.getDouble("lambda_initial");
  if (rel_tolerance_ < 0 || dx_tolerance_ < 0) throw Error("cholesky: tolerances must be >= 0");
  if (lambda_initial_ <= 0) throw Error("cholesky: option lambda_initial must be > 0");
  dormant_ = DormantPolicy::fromOptions(options, "cholesky");
  const std::string& ordering =
      options.getChoice("ordering", {"block_amd", "block_colamd", "amd", "metis", "natural"});
  block_ordering_ = ordering == "block_amd"      ? kBlockAmd
                    : ordering == "block_colamd" ? kBlockColamd
                                                 : kScalar;
  const int scalar = ordering == "metis"     ? CHOLMOD_METIS
                     : ordering == "natural" ? CHOLMOD_NATURAL
                                             : CHOLMOD_AMD;
  cholmod_common* c = common_.get();
  c->nmethods = 1;
  c->method[0].ordering = block_ordering_ == kScalar ? scalar : CHOLMOD_GIVEN;
  c->postorder = ordering != "natural";
  const std::string& method =
      options.getChoice("factorization", {"simplicial", "supernodal", "auto"});
  c->supernodal = method == "simplicial"   ? CHOLMOD_SIMPLICIAL
                  : method == "supernodal" ? CHOLMOD_SUPERNODAL
                                           : CHOLMOD_AUTO;
}

void CholeskyBackend::addStep(const Step& step) {
  checkStep(step, values_[current_], "cholesky");

  for (Key key : step.fixed) {
    if (!layout_.contains(key)) continue;
    const int i = layout_.index(key);
    if (layout_.fixed(i)) continue;
    // A known variable is fixed at its current estimate, in both copies.
    const Variable& v = variables_[i];
    std::copy(v.data[current_], v.data[current_] + v.size, v.data[1 - current_]);
  }
  // A fixed variable keeps its value and has no column (step.h).
  const bool refixed = layout_.add(step);
  for (Key key : step.new_values.keys()) {
    const Values::Entry& entry = step.new_values.entry(key);
    values_[0].insertEntry(key, entry);
    values_[1].insertEntry(key, entry);
    Variable v;
    v.size = dimension(entry.type);
    v.data[0] = values_[0].data(key);
    v.data[1] = values_[1].data(key);
    const int index = static_cast<int>(variables_.size());
    variables_.push_back(std::move(v));
    // Every variable has its diagonal block, so one that no factor touches
    // is a zero column: not positive definite, reported, never skipped.
    blockFor(index, index);
    pattern_dirty_ = true;
  }
  if (refixed) relayout();
  for (const FactorPtr& f : step.new_factors) {
    FactorSlot slot;
    slot.factor = f;
    slot.modes = asMultiModal(*f);
    for (Key key : f->keys()) slot.vars.push_back(layout_.index(key));
    if (slot.modes) {
      moded_.push_back(factors_.size());
      slot.dormant = dormantAt(slot, current_);
      dormant_count_ += slot.dormant;
    }
    if (!slot.dormant) addFactorBlocks(&slot);
    factors_.push_back(std::move(slot));
    pattern_dirty_ = true;
  }
}

void CholeskyBackend::addFactorBlocks(FactorSlot* slot) {
  const std::vector<int>& vars = slot->vars;
  const std::size_t n = vars.size();
  slot->blocks.clear();
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a; b < n; ++b)
      slot->blocks.push_back(blockFor(std::min(vars[a], vars[b]), std::max(vars[a], vars[b])));
}

void CholeskyBackend::relayoutBlocks() {
  blocks_.clear();
  block_index_.clear();
  for (Variable& v : variables_) v.blocks.clear();
  for (std::size_t i = 0; i < variables_.size(); ++i)
    blockFor(static_cast<int>(i), static_cast<int>(i));
  for (FactorSlot& slot : factors_) {
    if (slot.dormant)
      slot.blocks.clear();
    else
      addFactorBlocks(&slot);
  }
  dirty_columns_.clear();
  for (std::size_t j = 0; j < variables_.size(); ++j) dirty_columns_.push_back(static_cast<int>(j));
  pattern_dirty_ = true;
}

bool CholeskyBackend::dormantAt(const FactorSlot& slot, int which) {
  if (!dormant_.enabled()) return false;
  parameters_.resize(slot.vars.size());
  for (std::size_t a = 0; a < slot.vars.size(); ++a)
    parameters_[a] = variables_[slot.vars[a]].data[which];
  return dormant_.dormantAt(*slot.modes, parameters_.data());
}

void CholeskyBackend::syncDormant(int which) {
  bool changed = false;
  dormant_count_ = 0;
  for (std::size_t fi : moded_) {
    FactorSlot& slot = factors_[fi];
    const bool dormant = dormantAt(slot, which);
    changed |= dormant != slot.dormant;
    slot.dormant = dormant;
    dormant_count_ += dormant;
  }
  if (changed) relayoutBlocks();
}

std::string CholeskyBackend::unconstrained(Key key) const {
  const int index = layout_.index(key);
  long dormant = 0;
  for (const FactorSlot& slot : factors_)
    if (slot.dormant && std::find(slot.vars.begin(), slot.vars.end(), index) != slot.vars.end())
      ++dormant;
  if (dormant == 0) return "nothing constrains it in that direction";
  return "nothing in the system constrains it in that direction: " + std::to_string(dormant) +
         " factor(s) on it are dormant (a mode with information below dormant_scale, such as "
         "a max-mixture's null hypothesis) and left out of H; dormant_scale=0 keeps every "
         "factor in the system";
}

long CholeskyBackend::patternNonzeros() const {
  return matrix_ ? static_cast<long>(
                       static_cast<const SuiteSparse_long*>(matrix_->p)[layout_.dimension()])
                 : 0;
}

void CholeskyBackend::relayout() {
  // Every block column's row offsets depend on the rows' widths.
  dirty_columns_.clear();
  for (std::size_t j = 0; j < variables_.size(); ++j) dirty_columns_.push_back(static_cast<int>(j));
  pattern_dirty_ = true;
}

int CholeskyBackend::blockFor(int i, int j) {
  const std::uint64_t id = (std::uint64_t(std::uint32_t(i)) << 32) | std::uint32_t(j);
  auto it = block_index_.find(id);
  if (it != block_index_.end()) return it->second;
  const int b = static_cast<int>(blocks_.size());
  blocks_.push_back({i, j, 0});
  block_index_.emplace(id, b);
  auto& column = variables_[j].blocks;
  column.insert(std::upper_bound(column.begin(), column.end(), std::make_pair(i, b)),
                std::make_pair(i, b));
  dirty_columns_.push_back(j);
  return b;
}

void CholeskyBackend::rebuildPattern() {
  for (int j : dirty_columns_) {
    long offset = 0;
    for (const auto& [i, b] : variables_[j].blocks) {
      blocks_[b].offset = offset;
      offset += layout_.width(i);
    }
  }
  dirty_columns_.clear();

  // Column c of variable j holds the rows of every block above the diagonal
  // block, then the diagonal block's rows down to c (upper triangle).
  const long dimension = layout_.dimension();
  const int nv = layout_.size();
  long nnz = 0;
  for (int j = 0; j < nv; ++j) {
    const long above = blocks_[variables_[j].blocks.back().second].offset;
    const long width = layout_.width(j);
    nnz += width * above + width * (width + 1) / 2;
  }
  cholmod_common* c = common_.get();
  factor_.reset();
  matrix_.reset(cholmod_l_allocate_sparse(dimension, dimension, nnz, 1, 1, 1, CHOLMOD_REAL, c), c);
  if (!matrix_) return;  // out of memory: reported by the caller through c->status
  auto* p = static_cast<SuiteSparse_long*>(matrix_->p);
  auto* rows = static_cast<SuiteSparse_long*>(matrix_->i);
  diagonal_.resize(dimension);
  long pos = 0;
  for (int j = 0; j < nv; ++j) {
    const Variable& v = variables_[j];
    const long above = blocks_[v.blocks.back().second].offset;
    const long column = layout_.column(j);
    for (int k = 0; k < layout_.width(j); ++k) {
      p[column + k] = pos;
      for (const auto& [i, b] : v.blocks) {
        const int count = i == blocks_[v.blocks.back().second].row_var ? k + 1 : layout_.width(i);
        for (int r = 0; r < count; ++r) rows[pos++] = layout_.column(i) + r;
      }
      diagonal_[column + k] = p[column + k] + above + k;
    }
  }
  p[dimension] = pos;
  std::fill_n(static_cast<double*>(matrix_->x), nnz, 0.0);
  for (auto& h : h_) h.assign(nnz, 0.0);
  for (auto& g : g_) g.setZero(dimension);
  rhs_.reset(cholmod_l_allocate_dense(dimension, 1, dimension, CHOLMOD_REAL, c), c);
  if (block_ordering_ == kScalar) {
    factor_.reset(cholmod_l_analyze(matrix_.get(), c), c);
  } else if (orderBlocks()) {
    factor_.reset(cholmod_l_analyze_p(matrix_.get(), scalar_permutation_.data(), nullptr, 0, c), c);
  }
  pattern_dirty_ = false;
}

bool CholeskyBackend::orderBlocks() {
  // The ordering of the variables, found on the graph of variables (one node
  // per variable, as Ceres and sqrt-SAM order), then expanded to their
  // scalar columns: a third of the nodes for AMD, and a block stays whole.
  cholmod_common* c = common_.get();
  const long nv = static_cast<long>(variables_.size());
  cholesky::Sparse pattern;
  if (block_ordering_ == kBlockAmd) {
    std::size_t nnz = 0;
    for (const Variable& v : variables_) nnz += v.blocks.size();
    pattern.reset(cholmod_l_allocate_sparse(nv, nv, nnz, 1, 1, 1, CHOLMOD_PATTERN, c), c);
    if (!pattern) return false;
    auto* p = static_cast<SuiteSparse_long*>(pattern->p);
    auto* rows = static_cast<SuiteSparse_long*>(pattern->i);
    long pos = 0;
    for (long j = 0; j < nv; ++j) {
      p[j] = pos;
      for (const auto& [i, b] : variables_[j].blocks) rows[pos++] = i;
    }
    p[nv] = pos;
  } else {
    // sqrt-SAM's choice: COLAMD on the block Jacobian, whose transpose has
    // one row per variable and one column per factor.
    std::size_t nnz = 0;
    for (const FactorSlot& f : factors_) nnz += f.vars.size();
    const long nf = static_cast<long>(factors_.size());
    pattern.reset(cholmod_l_allocate_sparse(nv, nf, nnz, 0, 1, 0, CHOLMOD_PATTERN, c), c);
    if (!pattern) return false;
    auto* p = static_cast<SuiteSparse_long*>(pattern->p);
    auto* rows = static_cast<SuiteSparse_long*>(pattern->i);
    long pos = 0;
    for (long f = 0; f < nf; ++f) {
      p[f] = pos;
      for (int v : factors_[f].vars) rows[pos++] = v;
    }
    p[nf] = pos;
  }
  block_permutation_.resize(nv);
  const int ok = block_ordering_ == kBlockAmd
                     ? cholmod_l_amd(pattern.get(), nullptr, 0, block_permutation_.data(), c)
                     : cholmod_l_colamd(pattern.get(), nullptr, 0, 1, block_permutation_.data(), c);
  if (!ok) return false;
  scalar_permutation_.clear();
  for (SuiteSparse_long b : block_permutation_)
    for (int k = 0; k < layout_.width(b); ++k) scalar_permutation_.push_back(layout_.column(b) + k);
  return true;
}

long CholeskyBackend::assemble(int which, std::vector<double>* h, Eigen::VectorXd* g, double* cost,
                               bool* switched) {
  std::fill(h->begin(), h->end(), 0.0);
  g->setZero();
  *cost = 0;
  *switched = false;
  const auto* p = static_cast<const SuiteSparse_long*>(matrix_->p);
  double* hx = h->data();
  Linearization& lin = linearization_;
  for (std::size_t fi = 0; fi < factors_.size(); ++fi) {
    const FactorSlot& slot = factors_[fi];
    const std::size_t n = slot.vars.size();
    parameters_.resize(n);
    for (std::size_t a = 0; a < n; ++a) parameters_[a] = variables_[slot.vars[a]].data[which];
    if (slot.modes)
      *switched |= dormant_.dormantAt(*slot.modes, parameters_.data()) != slot.dormant;
    if (!linearize(*slot.factor, parameters_.data(), &lin)) return static_cast<long>(fi);
    *cost += lin.cost;
    // A dormant factor is in the objective, not in the linear system.
    if (slot.dormant) continue;
    const long m = lin.residual.size();
    for (std::size_t a = 0; a < n; ++a) {
      const int va = slot.vars[a];
      const long column = layout_.column(va);
      const auto& ja = lin.jacobians[a];
      for (int r = 0; r < layout_.width(va); ++r) {
        double s = 0;
        for (long q = 0; q < m; ++q) s += ja(q, r) * lin.residual[q];
        (*g)[column + r] += s;
      }
    }
    std::size_t pair = 0;
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a; b < n; ++b, ++pair) {
        const Block& block = blocks_[slot.blocks[pair]];
        // The block is (row variable, column variable) with row <= column:
        // add Jr^T Jc where Jr, Jc are the Jacobians of those two keys.
        const bool swap = slot.vars[a] > slot.vars[b];
        const auto& jr = lin.jacobians[swap ? b : a];
        const auto& jc = lin.jacobians[swap ? a : b];
        const long column = layout_.column(block.col_var);
        const int columns = layout_.width(block.col_var);
        const int rows = layout_.width(block.row_var);
        const bool diagonal = block.row_var == block.col_var;
        for (int k = 0; k < columns; ++k) {
          double* dst = hx + p[column + k] + block.offset;
          const int count = diagonal ? k + 1 : rows;
          for (int r = 0; r < count; ++r) {
            double s = 0;
            for (long q = 0; q < m; ++q) s += jr(q, r) * jc(q, k);
            // Two different keys of one factor on the same variable: H gets
            // Ja^T Jb + Jb^T Ja; the loop meets the pair once.
            if (diagonal && a != b)
              for (long q = 0; q < m; ++q) s += jc(q, r) * jr(q, k);
            dst[r] += s;
          }
        }
      }
    }
  }
  return -1;
}

double CholeskyBackend::weakestPivot(long* weakest_column) const {
  // The pivot (L_jj^2 of LL^T, D_j of LDL^T) is what is left of H_jj once
  // the earlier columns are eliminated: a column that depends on them (a
  // singular system) keeps only rounding, ~1e-16 of H_jj, where a
  // constrained one keeps far more (>= 1.5e-7 of it on every public dataset,
  // from odometry and at the optimum).
  const cholmod_factor* L = factor_.get();
  const auto* x = static_cast<const double*>(L->x);
  const auto* perm = static_cast<const SuiteSparse_long*>(L->Perm);
  const auto* hx = static_cast<const double*>(matrix_->x);
  double lo = std::numeric_limits<double>::infinity();
  long lo_column = 0;
  auto visit = [&](long k, double pivot) {
    const double hjj = hx[diagonal_[perm ? perm[k] : k]];
    const double ratio = hjj > 0 ? pivot / hjj : 0;
    if (ratio < lo || std::isnan(ratio)) {
      lo = std::isnan(ratio) ? 0 : ratio;
      lo_column = k;
    }
  };
  if (L->is_super) {
    // Each supernode is a dense column-major block whose first nscol rows
    // are its own columns: the diagonal is at j * (nsrow + 1).
    const auto* super = static_cast<const SuiteSparse_long*>(L->super);
    const auto* pi = static_cast<const SuiteSparse_long*>(L->pi);
    const auto* px = static_cast<const SuiteSparse_long*>(L->px);
    for (std::size_t s = 0; s < L->nsuper; ++s) {
      const long nscol = super[s + 1] - super[s];
      const long nsrow = pi[s + 1] - pi[s];
      for (long j = 0; j < nscol; ++j) {
        const double d = x[px[s] + j * (nsrow + 1)];
        visit(super[s] + j, d * d);
      }
    }
  } else {
    // Simplicial: each column starts with its diagonal entry (L_jj, or D_j
    // for LDL^T, which may come out <= 0 without CHOLMOD stopping).
    const auto* lp = static_cast<const SuiteSparse_long*>(L->p);
    for (std::size_t k = 0; k < L->n; ++k) {
      const double d = x[lp[k]];
      visit(static_cast<long>(k), L->is_ll ? d * d : d);
    }
  }
  *weakest_column = perm ? perm[lo_column] : lo_column;
  return lo;
}

std::string CholeskyBackend::illConditioning() {
  // A factor's scale is the largest diagonal entry of its J^T J (whitened
  // Jacobian): what it adds to H. Compared with the median factor's, a
  // ratio past ~1/singular_tolerance leaves pivots at rounding level even
  // where every direction is constrained.
  constexpr double kExtremeRatio = 1e6;
  std::vector<double> scales;
  double largest = 0;
  std::size_t largest_at = 0;
  for (std::size_t fi = 0; fi < factors_.size(); ++fi) {
    const FactorSlot& slot = factors_[fi];
    if (slot.dormant) continue;  // not in H
    parameters_.resize(slot.vars.size());
    for (std::size_t a = 0; a < slot.vars.size(); ++a)
      parameters_[a] = variables_[slot.vars[a]].data[current_];
    if (!linearize(*slot.factor, parameters_.data(), &linearization_)) continue;
    double scale = 0;
    for (const auto& j : linearization_.jacobians)
      if (j.size() > 0) scale = std::max(scale, j.colwise().squaredNorm().maxCoeff());
    scales.push_back(scale);
    if (scale > largest) {
      largest = scale;
      largest_at = fi;
    }
  }
  if (scales.empty()) return "";
  std::nth_element(scales.begin(), scales.begin() + scales.size() / 2, scales.end());
  const double median = scales[scales.size() / 2];
  if (!(largest > kExtremeRatio * median)) return "";
  const Factor& f = *factors_[largest_at].factor;
  return "the system is ill-conditioned, not unconstrained: factor " + f.tag() + " on " +
         keyList(f.keys()) + " weighs " + scientific(largest) + " in H, " +
         scientific(largest / std::max(median, std::numeric_limits<double>::min())) +
         " times the median factor (" + scientific(median) +
         "); is its information matrix meant to be that large?";
}

bool CholeskyBackend::factorize(const std::vector<double>& h, double lambda, Status* status) {
  cholmod_common* c = common_.get();
  auto* x = static_cast<double*>(matrix_->x);
  std::copy(h.begin(), h.end(), x);
  if (lambda > 0)
    for (long d : diagonal_) x[d] += lambda * std::max(h[d], kMinDiagonal);
  c->status = CHOLMOD_OK;
  const int ok = cholmod_l_factorize(matrix_.get(), factor_.get(), c);
  if (ok && c->status == CHOLMOD_OK && factor_->minor == factor_->n) {
    // CHOLMOD stops only at a pivot <= 0; rounding usually leaves a tiny
    // positive one where the system is singular.
    long weakest = 0;
    const double pivot = weakestPivot(&weakest);
    if (!(pivot < singular_tolerance_)) return true;
    pattern_dirty_ = true;
    const int variable = layout_.variableOfColumn(weakest);
    const Key key = layout_.key(variable);
    const std::string ill = illConditioning();
    *status = Status::numericalFailure(
        "cholesky: the normal equations are numerically singular at variable " + key.str() +
            " (component " + std::to_string(weakest - layout_.column(variable)) + " of " +
            typeName(values_[current_].type(key)) + "): its pivot is " + scientific(pivot) +
            " of its diagonal, below singular_tolerance (reciprocal condition estimate " +
            scientific(cholmod_l_rcond(factor_.get(), c)) + "); " +
            (ill.empty() ? unconstrained(key) : ill),
        {key});
    return false;
  }
  // The next factorisation starts again from a fresh symbolic analysis.
  pattern_dirty_ = true;
  if (c->status == CHOLMOD_NOT_POSDEF || (ok && factor_->minor < factor_->n)) {
    const long minor = static_cast<long>(factor_->minor);
    const auto* perm = static_cast<const SuiteSparse_long*>(factor_->Perm);
    const long column = perm ? perm[minor] : minor;
    const int variable = layout_.variableOfColumn(column);
    const Key key = layout_.key(variable);
    const std::string ill = illConditioning();
    *status = Status::numericalFailure(
        "cholesky: the normal equations are not positive definite at variable " + key.str() +
            " (component " + std::to_string(column - layout_.column(variable)) + " of " +
            typeName(values_[current_].type(key)) +
            "): " + (ill.empty() ? unconstrained(key) : ill),
        {key});
    return false;
  }
  *status = Status::numericalFailure("cholesky: CHOLMOD factorisation failed with status " +
                                     std::to_string(c->status));
  return false;
}

UpdateResult CholeskyBackend::update(const Step& step) {
  UpdateResult result = solve(step);
  last_status_ = result.status;
  return result;
}

Status CholeskyBackend::jointMarginalCovariance(const std::vector<Key>& keys,
                                                Eigen::MatrixXd* covariance) {
  const long size = checkMarginalKeys(keys, values_[current_], "cholesky");
  if (!last_status_.ok())
    return Status::numericalFailure(
        "cholesky: no marginal covariance: the last update did not end ok (" +
            last_status_.message + ")",
        last_status_.keys);
  // The scalar columns of H asked for, and where each lands in the result.
  std::vector<long> columns, places;
  long place = 0;
  for (Key key : keys) {
    const int i = layout_.index(key);
    for (int k = 0; k < layout_.width(i); ++k) {
      columns.push_back(layout_.column(i) + k);
      places.push_back(place + k);
    }
    place += values_[current_].dim(key);
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(size, size);
  if (columns.empty()) {  // fixed variables only
    *covariance = out;
    return Status();
  }
  cholmod_common* c = common_.get();
  if (pattern_dirty_) rebuildPattern();
  if (!matrix_ || !factor_ || !rhs_) {
    pattern_dirty_ = true;
    return Status::numericalFailure("cholesky: CHOLMOD could not analyse the system (status " +
                                    std::to_string(c->status) + ")");
  }
  double cost = 0;
  bool switched = false;
  const long bad = assemble(current_, &h_[current_], &g_[current_], &cost, &switched);
  if (bad >= 0) {
    const auto& fkeys = factors_[bad].factor->keys();
    return Status::numericalFailure("cholesky: factor " + factors_[bad].factor->tag() + " on " +
                                        keyList(fkeys) + " cannot be evaluated at the estimate",
                                    fkeys);
  }
  Status status;
  if (!factorize(h_[current_], 0, &status)) return status;
  const long n = layout_.dimension();
  const long k = static_cast<long>(columns.size());
  cholesky::Dense unit(cholmod_l_zeros(n, k, CHOLMOD_REAL, c), c);
  if (!unit)
    return Status::numericalFailure("cholesky: CHOLMOD could not allocate the unit vectors");
  for (long j = 0; j < k; ++j) static_cast<double*>(unit->x)[j * n + columns[j]] = 1;
  cholesky::Dense x(cholmod_l_solve(CHOLMOD_A, factor_.get(), unit.get(), c), c);
  if (!x)
    return Status::numericalFailure("cholesky: CHOLMOD solve failed with status " +
                                    std::to_string(c->status));
  const auto* xv = static_cast<const double*>(x->x);
  for (long j = 0; j < k; ++j)
    for (long i = 0; i < k; ++i) out(places[i], places[j]) = xv[j * n + columns[i]];
  out = (0.5 * (out + out.transpose())).eval();
  if (!out.allFinite())
    return Status::numericalFailure("cholesky: the marginal covariance is not finite", keys);
  *covariance = std::move(out);
  return Status();
}

UpdateResult CholeskyBackend::solve(const Step& step) {
  PhaseClock clock;
  UpdateResult result;
  addStep(step);
  result.variables = variables_.size();
  clock.lap(&result.time.other);
  const long dimension = layout_.dimension();
  if (dimension == 0) {
    clock.finish(&result.time);
    return result;
  }

  cholmod_common* c = common_.get();
  // The pattern and its symbolic analysis, when factors came, left or
  // went dormant; false (with the status set) when CHOLMOD fails.
  auto analyse = [&]() {
    if (!pattern_dirty_) return true;
    rebuildPattern();
    clock.lap(&result.time.order);
    if (matrix_ && factor_ && rhs_) return true;
    pattern_dirty_ = true;
    result.status =
        Status::numericalFailure("cholesky: CHOLMOD could not analyse the system (status " +
                                 std::to_string(c->status) + ")");
    return false;
  };
  if (!analyse()) {
    clock.finish(&result.time);
    return result;
  }
  result.kind = UpdateKind::kBatch;
  result.reason = "sqrt-SAM: batch solve at every update";
  result.variables_relinearized = variables_.size();
  result.columns_total = result.columns_recomputed = static_cast<std::size_t>(dimension);

  int cur = current_;
  double cost = 0;
  bool switched = false;
  const long bad = assemble(cur, &h_[cur], &g_[cur], &cost, &switched);
  clock.lap(&result.time.linearize);
  if (bad >= 0) {
    const auto& keys = factors_[bad].factor->keys();
    result.status =
        Status::numericalFailure("cholesky: factor " + factors_[bad].factor->tag() + " on " +
                                     keyList(keys) + " cannot be evaluated at the current estimate",
                                 keys);
    clock.finish(&result.time);
    return result;
  }
  if (!std::isfinite(cost)) {
    // Every factor is finite but their sum is not: no step could be judged.
    std::vector<FactorPtr> factors;
    for (const FactorSlot& slot : factors_) factors.push_back(slot.factor);
    result.status = finiteCostStatus(cost, factors, values_[cur], "cholesky");
    clock.finish(&result.time);
    return result;
  }

  double lambda = 0;
  bool converged = false;
  for (int it = 0; it < max_iterations_ && !converged; ++it) {
    ++result.iterations;
    const bool factored = factorize(h_[cur], lambda, &result.status);
    clock.lap(&result.time.factor);
    if (!factored) break;

    Eigen::Map<Eigen::VectorXd>(static_cast<double*>(rhs_->x), dimension) = -g_[cur];
    cholmod_l_solve2(CHOLMOD_A, factor_.get(), rhs_.get(), nullptr, solution_.out(c), nullptr,
                     work_y_.out(c), work_e_.out(c), c);
    if (!solution_) {
      result.status = Status::numericalFailure("cholesky: CHOLMOD solve failed with status " +
                                               std::to_string(c->status));
      break;
    }
    const Eigen::Map<const Eigen::VectorXd> dx(static_cast<const double*>(solution_->x), dimension);
    if (!dx.allFinite()) {
      result.status = Status::numericalFailure("cholesky: the Gauss-Newton step is not finite");
      break;
    }
    // Decrease the quadratic model predicts: -g.dx - dx.H.dx / 2, which with
    // (H + lambda D) dx = -g is (-g.dx + lambda dx.D.dx) / 2.
    double predicted = -g_[cur].dot(dx);
    if (lambda > 0)
      for (long i = 0; i < dimension; ++i)
        predicted += lambda * std::max(h_[cur][diagonal_[i]], kMinDiagonal) * dx[i] * dx[i];
    predicted *= 0.5;
    double x_norm = 0;
    for (const Variable& v : variables_)
      for (int k = 0; k < v.size; ++k) x_norm += v.data[cur][k] * v.data[cur][k];
    x_norm = std::sqrt(x_norm);
    const bool tiny =
        predicted <= rel_tolerance_ * cost || dx.norm() <= dx_tolerance_ * (x_norm + dx_tolerance_);
    if (tiny) {
      // A tiny Gauss-Newton step is where the quadratic model is exact:
      // take it without paying for another linearisation. A tiny damped
      // step means no step lowers the cost any more: stop where we are.
      if (lambda == 0) layout_.retract(&values_[cur], dx.data());
      clock.lap(&result.time.solve);
      converged = true;
      break;
    }
    const int other = 1 - cur;
    for (const Variable& v : variables_)
      std::copy(v.data[cur], v.data[cur] + v.size, v.data[other]);
    layout_.retract(&values_[other], dx.data());
    clock.lap(&result.time.solve);

    double new_cost = std::numeric_limits<double>::infinity();
    if (assemble(other, &h_[other], &g_[other], &new_cost, &switched) >= 0)
      new_cost = std::numeric_limits<double>::infinity();
    clock.lap(&result.time.linearize);
    if (new_cost < cost) {
      const double decrease = cost - new_cost;
      cur = current_ = other;
      if (decrease <= rel_tolerance_ * cost) converged = true;
      cost = new_cost;
      lambda = lambda / 10 < kMinLambda ? 0 : lambda / 10;
      if (switched && !converged) {
        // H was assembled with the old dormant set: lay the pattern out for
        // the new one and assemble it again at the accepted point.
        syncDormant(cur);
        clock.lap(&result.time.other);
        if (!analyse()) break;
        assemble(cur, &h_[cur], &g_[cur], &new_cost, &switched);
        clock.lap(&result.time.linearize);
      }
    } else {
      lambda = lambda == 0 ? lambda_initial_ : lambda * 10;
      if (lambda > kMaxLambda) converged = true;
    }
  }
  // The last step may have been taken without a linearisation: the dormant
  // set of the estimate this update returns (laid out for the next one).
  syncDormant(current_);
  if (result.status.ok() && !converged) {
    result.status.code = Status::kNotConverged;
    result.status.message = "cholesky: not converged after " + std::to_string(max_iterations_) +
                            " iterations (cost " + std::to_string(cost) + ")";
  }
  clock.finish(&result.time);
  return result;
}

void registerCholeskyBackend(Registry& registry) {
  BackendInfo info;
  info.name = "cholesky";
  info.description =
      "sqrt-SAM-Chol (thesis sec. 3.5.1): Gauss-Newton (LM fallback) on the full normal "
      "equations, relinearised and solved with CHOLMOD sparse Cholesky at every update";
  info.options = CholeskyBackend::optionSpecs();
  info.create = [](const Options& options) -> std::unique_ptr<Backend> {
    return std::make_unique<CholeskyBackend>(options);
  };
  registry.addBackend(std::move(info));
}

}  // namespace hamal
