// AprilSamBackend: see aprilsam_backend.h (thesis ch. 3, Alg. 3.1).
#include "backends/aprilsam/aprilsam_backend.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <unordered_set>

#include "backends/aprilsam/bhamd_ordering.h"
#include "backends/aprilsam/dense_blocks.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/aprilsam/ordering_input.h"
#include "core/error.h"
#include "core/finite_result.h"
#include "core/pose2.h"
#include "core/stopwatch.h"
#include "factors/max_mixture_factor.h"

namespace hamal::aprilsam {

namespace {
// The option values, in the order of AprilSamOptions' enums.
const std::vector<std::string> kOrderings = {"minheap", "bhamd", "amd", "natural"};
const std::vector<std::string> kBacksolves = {"partial", "full"};
const std::vector<std::string> kFactorUpdates = {"rank", "refactor"};
const std::vector<std::string> kReeliminates = {"full", "top"};

template <typename Enum>
Enum choice(const Options& o, const std::string& name, const std::vector<std::string>& names) {
  const std::string value = o.getChoice(name, names);
  return static_cast<Enum>(std::find(names.begin(), names.end(), value) - names.begin());
}
template <typename Enum>
const std::string& name(Enum value, const std::vector<std::string>& names) {
  return names.at(static_cast<std::size_t>(value));
}

// Shortest round-tripping form: std::to_string's fixed six decimals would
// turn 1e-9 into "0", and the listed default is the value the back-end gets.
std::string num(double v) {
  std::ostringstream os;
  for (int prec = 1;; ++prec) {
    os.str("");
    os << std::setprecision(prec) << v;
    if (prec >= 17 || std::stod(os.str()) == v) return os.str();
  }
}
}  // namespace

std::vector<OptionSpec> AprilSamOptions::optionSpecs() {
  const AprilSamOptions d;
  std::vector<OptionSpec> specs = UpdatePolicy::optionSpecs();
  specs.push_back({"ordering", name(d.ordering, kOrderings),
                   "batch ordering (sec. 3.4.3): minheap (Alg. 3.2, score eq. 3.20), bhamd "
                   "(newest node last, BHAMD on the rest: AprilSAM-NoPredictiveOrder), amd "
                   "(SuiteSparse AMD), natural (order of arrival)"});
  specs.push_back(
      {"loop_closure_radius", num(d.loop_closure_radius),
       "R_T (eq. 3.20), metres: nodes within it of the newest pose are ordered "
       "last by minheap and, with n_lc=0, counted as n_lc (COUNTPOSSIBLELOOPCLOSURENODES, "
       "Alg. 3.1 line 9) by the time criterion. The thesis gives no value"});
  specs.push_back({"n_lc", std::to_string(d.n_lc),
                   "n_lc of the time criterion (Alg. 3.1 line 10): 0 counts the nodes within "
                   "R_T of the newest pose, as the thesis states it; a positive value fixes it, "
                   "as the reference implementation does (3). Counting finds many nodes in "
                   "revisited areas, so the time criterion then batches at almost every loop "
                   "closure"});
  specs.push_back(
      {"factor_update", name(d.factor_update, kFactorUpdates),
       "how an incremental step updates R on the affected rows (the same rows, the same R~ "
       "to rounding): rank (Householder reflections of the new Jacobian rows into R, O(k w) "
       "for a row of width w and k new rows) or refactor (form R_aff^T R_aff + A_new and "
       "factor it, eq. 3.14 as the thesis writes it, O(w^2) per row)"});
  specs.push_back({"rank_update_max_rows", std::to_string(d.rank_update_max_rows),
                   "with factor_update=rank, a step with more new Jacobian rows than this is "
                   "refactored instead (the reflections' cost grows with the rows)"});
  specs.push_back({"backsolve", name(d.backsolve, kBacksolves),
                   "back-substitution (sec. 3.4.2, fig. 3.7): partial (only the rows an "
                   "update changes) or full (every row: AprilSAM-FullSolve)"});
  specs.push_back({"backsolve_tol", num(d.backsolve_tol),
                   "partial back-substitution: propagate a change of dx_k to the rows below "
                   "only when it exceeds this (inf-norm), as GTSAM's wildfire threshold (also "
                   "1e-3). 0 = exact, bit for bit the full solve; a larger value skips more small "
                   "changes, trading a little accuracy for time"});
  specs.push_back(
      {"batch_first", d.batch_first ? "true" : "false",
       "ask the criteria that do not depend on the step's solve (the time criterion, with "
       "the flops the rank update would report, computed from the structure; the periodic "
       "one) before the incremental update, and batch without it when they are met. Alg. "
       "3.1 updates first; skipping that update, which the batch refactors away, takes a "
       "quarter off a batch step, but the batch then starts from the estimate before it, "
       "so the run differs (factor_update=rank and the deterministic cost only). With "
       "reeliminate=top the time criterion re-eliminates the top there instead"});
  specs.push_back({"batch_iterations", std::to_string(d.batch_iterations),
                   "Gauss-Newton steps per batch update (Alg. 3.1 lines 12-16 and the "
                   "reference code take 1)"});
  specs.push_back({"damping", num(d.damping),
                   "lambda of the Levenberg-damped batch (A_ii += lambda diag(A_ii)) used "
                   "when a factorisation meets a block that is not positive definite"});
  specs.push_back(
      {"dormant_scale", num(d.dormant_scale),
       "a factor with modes whose mode at its linearisation point carries less information "
       "than this fraction of its nominal one (a max-mixture's null hypothesis, e.g. 1e-12) "
       "is kept out of R and the ordering until the switch hook finds another mode active: "
       "the dropped term's gradient is that fraction of the nominal's. 0 keeps every factor "
       "in the system"});
  specs.push_back(
      {"reeliminate", name(d.reeliminate, kReeliminates),
       "what a batch decision of the policy re-eliminates: full (Alg. 3.1 lines 12-16: "
       "every variable relinearised, reordered, refactored) or top (iSAM2's way: only the "
       "rows the factors added since the last re-elimination and the variables in L reach, "
       "with their ancestors, reordered by minheap and refactored from the factors and the "
       "kept rows' marginals; the top's variables move to the estimate unless a factor ties "
       "them to a kept row). top falls back to full for factors with modes, after a damped "
       "batch, or when the top is more than top_share of R; it needs ordering=minheap"});
  specs.push_back(
      {"top_relinearize", num(d.top_relinearize),
       "reeliminate=top: the top is taken from the variables whose change |dx_i| (2-norm) "
       "reaches this fraction of delta_T, besides those in L (1: L alone, iSAM2's rule). "
       "With L alone a variable that settles just below delta_T is never relinearised, "
       "which a full batch would do"});
  specs.push_back({"top_share", num(d.top_share),
                   "reeliminate=top: a top of more than this share of R's rows is re-eliminated "
                   "by a full batch instead (which also relinearises and reorders the rest)"});
  return specs;
}

AprilSamOptions AprilSamOptions::fromOptions(const Options& o) {
  AprilSamOptions a;
  a.policy = UpdatePolicy::fromOptions(o);
  a.ordering = choice<AprilSamOptions::Ordering>(o, "ordering", kOrderings);
  a.loop_closure_radius = o.getDouble("loop_closure_radius");
  a.n_lc = o.getInt("n_lc");
  a.factor_update = choice<AprilSamOptions::FactorUpdate>(o, "factor_update", kFactorUpdates);
  a.rank_update_max_rows = o.getInt("rank_update_max_rows");
  a.backsolve = choice<AprilSamOptions::Backsolve>(o, "backsolve", kBacksolves);
  a.backsolve_tol = o.getDouble("backsolve_tol");
  a.batch_iterations = o.getInt("batch_iterations");
  a.batch_first = o.getBool("batch_first");
  a.damping = o.getDouble("damping");
  a.dormant_scale = o.getDouble("dormant_scale");
  a.reeliminate = choice<AprilSamOptions::Reeliminate>(o, "reeliminate", kReeliminates);
  a.top_share = o.getDouble("top_share");
  a.top_relinearize = o.getDouble("top_relinearize");
  const std::string who = o.owner().empty() ? "aprilsam" : o.owner();
  if (!(a.loop_closure_radius >= 0) || !std::isfinite(a.loop_closure_radius))
    throw Error(who + ": option loop_closure_radius must be a finite number >= 0");
  if (a.n_lc < 0) throw Error(who + ": option n_lc must be >= 0");
  if (!(a.backsolve_tol >= 0) || !std::isfinite(a.backsolve_tol))
    throw Error(who + ": option backsolve_tol must be a finite number >= 0");
  if (a.rank_update_max_rows < 0) throw Error(who + ": option rank_update_max_rows must be >= 0");
  if (a.batch_iterations < 1) throw Error(who + ": option batch_iterations must be >= 1");
  if (!(a.damping > 0) || !std::isfinite(a.damping))
    throw Error(who + ": option damping must be a finite number > 0");
  if (!(a.dormant_scale >= 0 && a.dormant_scale < 1))
    throw Error(who + ": option dormant_scale must be a number in [0, 1)");
  if (!(a.top_relinearize > 0 && a.top_relinearize <= 1))
    throw Error(who + ": option top_relinearize must be a number in (0, 1]");
  if (!(a.top_share >= 0 && a.top_share <= 1))
    throw Error(who + ": option top_share must be a number in [0, 1]");
  if (a.reeliminate == Reeliminate::kTop && a.ordering != Ordering::kMinHeap)
    throw Error(who +
                ": option reeliminate=top needs ordering=minheap (the top is reordered "
                "by the min-heap ordering)");
  return a;
}

AprilSamBackend::AprilSamBackend(AprilSamOptions options)
    : options_(std::move(options)), policy_(options_.policy) {
  factor_begin_.push_back(0);
}

Eigen::Vector2d AprilSamBackend::location(int v) const {
  return {lin_[v].data[0], lin_[v].data[1]};
}

Eigen::Vector2d AprilSamBackend::orderingPosition(int v) const {
  // A non-finite location is put far away, so the min-heap's distance test
  // (eq. 3.20) neither reads NaN nor counts it near the newest pose.
  const Eigen::Vector2d p = location(v);
  return p.allFinite() ? p : Eigen::Vector2d::Constant(1e300);
}

namespace {
// A grid coordinate, clamped so that a far-off (or diverged) estimate still
// converts to an integer without overflow.
long cellIndex(double coordinate, double r) {
  constexpr double kLimit = 1e15;
  return static_cast<long>(std::clamp(std::floor(coordinate / r), -kLimit, kLimit));
}

// Packs two grid coordinates, negative ones included, into one hash key.
// Shifting a negative long is undefined: the packing is done unsigned.
long cellKey(long cx, long cy) {
  const unsigned long packed =
      (static_cast<unsigned long>(cx) << 32) ^ (static_cast<unsigned long>(cy) & 0xffffffffUL);
  return static_cast<long>(packed);
}
}  // namespace

long AprilSamBackend::gridCell(double x, double y) const {
  const double r = options_.loop_closure_radius;
  return cellKey(cellIndex(x, r), cellIndex(y, r));
}

void AprilSamBackend::gridInsert(int v) {
  if (options_.loop_closure_radius <= 0) return;
  const Eigen::Vector2d p = location(v);
  if (!p.allFinite()) return;
  grid_[gridCell(p.x(), p.y())].push_back(v);
}

// COUNTPOSSIBLELOOPCLOSURENODES (Alg. 3.1 line 10): the nodes within R_T of
// the newest pose, at their linearisation points, found through a grid of
// R_T cells so the count costs the neighbourhood, not the map.
long AprilSamBackend::countPossibleLoopClosureNodes() const {
  if (options_.n_lc > 0) return options_.n_lc;
  const double r = options_.loop_closure_radius;
  if (r <= 0 || newest_pose_ < 0) return 0;
  const Eigen::Vector2d c = location(newest_pose_);
  if (!c.allFinite()) return 0;
  const long cx = cellIndex(c.x(), r);
  const long cy = cellIndex(c.y(), r);
  long count = 0;
  for (long dx = -1; dx <= 1; ++dx)
    for (long dy = -1; dy <= 1; ++dy) {
      auto it = grid_.find(cellKey(cx + dx, cy + dy));
      if (it == grid_.end()) continue;
      for (int v : it->second)
        if (v != newest_pose_ && (location(v) - c).norm() < r) ++count;
    }
  return count;
}

bool AprilSamBackend::gatherFactor(std::size_t f, bool at_lin_point) {
  const int b = factor_begin_[f], e = factor_begin_[f + 1];
  params_.resize(e - b);
  fpos_.resize(e - b);
  fdims_.resize(e - b);
  bool touches_fixed = false;
  for (int k = b; k < e; ++k) {
    const int v = factor_vars_[k];
    params_[k - b] = at_lin_point ? lin_[v].data.data() : est_[v];
    fpos_[k - b] = pos_of_[v];
    fdims_[k - b] = dims_[v];
    touches_fixed |= pos_of_[v] < 0;
  }
  return touches_fixed;
}

bool AprilSamBackend::linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                                        UpdateResult* result) {
  if (!linearize(factor, params_.data(), &lin_scratch_)) {
    result->status = Status::numericalFailure(
        "aprilsam: a " + factors_[f]->tag() +
            " factor does not evaluate to finite numbers at the linearisation point",
        factors_[f]->keys());
    return false;
  }
  if (touches_fixed) {
    // A fixed variable has no column: its Jacobian block is dropped, its
    // value stays in the residual.
    const int nk = static_cast<int>(fpos_.size());
    int kept = 0;
    for (int k = 0; k < nk; ++k) {
      if (fpos_[k] < 0) continue;
      if (kept != k) lin_scratch_.jacobians[kept] = std::move(lin_scratch_.jacobians[k]);
      fpos_[kept] = fpos_[k];
      fdims_[kept] = fdims_[k];
      ++kept;
    }
    lin_scratch_.jacobians.resize(kept);
  }
  return true;
}

bool AprilSamBackend::linearizeFactor(std::size_t f, double sign, bool as_rows,
                                      UpdateResult* result) {
  const bool touches_fixed = gatherFactor(f, true);
  const Factor* evaluated = factors_[f].get();
  if (factors_[f]->hasModes()) {
    // The mode R holds the factor with: the one at the linearisation point
    // when it goes in, the recorded one when it comes out (the point has not
    // moved since, so they are the same unless a raised switch put the
    // nominal component in at the same point: then it is the nominal that
    // comes out).
    const int m =
        sign > 0 && !modes_at_lin_known_ ? factors_[f]->mode(params_.data()) : lin_mode_[f];
    if (sign > 0) {
      lin_mode_[f] = m;
      held_nominal_[f] = 0;
    }
    if (dormant(f, m)) {
      lin_scratch_.cost = 0;
      return true;
    }
    if (sign < 0 && held_nominal_[f]) evaluated = nominalComponent(f);
  }
  const double w = sign > 0 ? weight_[f] : lin_weight_[f];
  if (sign > 0) lin_weight_[f] = w;
  if (w == 0) {
    lin_scratch_.cost = 0;
    return true;
  }
  if (!linearizeGathered(f, *evaluated, touches_fixed, result)) return false;
  if (w != 1) scaleScratch(w);
  if (lin_scratch_.jacobians.empty()) return true;
  if (as_rows)
    rows_.add(lin_scratch_, fpos_.data(), fdims_.data());
  else
    neq_.add(lin_scratch_, fpos_.data(), fdims_.data(), sign);
  return true;
}

const Factor* AprilSamBackend::nominalComponent(std::size_t f) const {
  return static_cast<const MaxMixtureFactor&>(*factors_[f]).components()[0].factor.get();
}

bool AprilSamBackend::raiseToNominal(std::size_t f, bool as_rows, UpdateResult* result) {
  // R holds held x (the nominal's J^T J, J^T r) at the linearisation point
  // (held = the null's scale, 0 when dormant); the nominal mode needs
  // 1 x: the difference is (1 - held) x, rows sqrt(1 - held) [J | r], a
  // rank update like a new factor's.
  const double held =
      dormant(f, lin_mode_[f]) ? 0.0 : factors_[f]->modeInformationScale(lin_mode_[f]);
  const double w = (1.0 - held) * lin_weight_[f];
  const bool touches_fixed = gatherFactor(f, true);
  if (!linearizeGathered(f, *nominalComponent(f), touches_fixed, result)) return false;
  lin_mode_[f] = 0;
  held_nominal_[f] = 1;
  if (lin_scratch_.jacobians.empty()) return true;
  if (as_rows) {
    const double s = std::sqrt(w);
    lin_scratch_.residual *= s;
    for (auto& j : lin_scratch_.jacobians) j *= s;
    rows_.add(lin_scratch_, fpos_.data(), fdims_.data());
  } else {
    neq_.add(lin_scratch_, fpos_.data(), fdims_.data(), w);
  }
  return true;
}

void AprilSamBackend::scaleScratch(double w) {
  const double s = std::sqrt(w);
  lin_scratch_.residual *= s;
  for (auto& j : lin_scratch_.jacobians) j *= s;
  lin_scratch_.cost *= w;
}

void AprilSamBackend::setFactorWeight(const Factor* factor, double weight) {
  const auto it = factor_index_.find(factor);
  if (it == factor_index_.end())
    throw Error("aprilsam: factor weight of a factor it does not hold");
  if (!(weight >= 0) || !std::isfinite(weight))
    throw Error("aprilsam: factor weight " + std::to_string(weight) +
                " is not a finite number >= 0");
  const int f = it->second;
  if (weight_[f] == weight) return;
  if (weight_[f] == lin_weight_[f]) reweighted_.push_back(f);
  weight_[f] = weight;
}

double AprilSamBackend::factorWeight(const Factor* factor) const {
  const auto it = factor_index_.find(factor);
  if (it == factor_index_.end())
    throw Error("aprilsam: factor weight of a factor it does not hold");
  return weight_[it->second];
}

bool AprilSamBackend::residualCovariance(const std::vector<const Factor*>& factors,
                                         Eigen::MatrixXd* g) {
  if (broken_ || damped_) return false;
  if (factors.empty()) {
    g->resize(0, 0);
    return true;
  }
  // Rows of J^T per position: B[p] is dim(p) x m, column-major. A factor
  // need not be held: its variables must be, and it is linearised at their
  // linearisation points.
  int m = 0;
  for (const Factor* factor : factors) {
    for (const Key& key : factor->keys())
      if (!index_.count(key)) return false;
    m += factor->residualDim();
  }
  std::unordered_map<int, std::vector<double>> b;
  Linearization lin;
  std::vector<const double*> params;
  int row = 0;
  for (const Factor* factor : factors) {
    params.clear();
    for (const Key& key : factor->keys()) params.push_back(lin_[index_.at(key)].data.data());
    if (!linearize(*factor, params.data(), &lin)) return false;
    const int rows = factor->residualDim();
    for (std::size_t k = 0; k < factor->keys().size(); ++k) {
      const int v = index_.at(factor->keys()[k]);
      const int p = pos_of_[v];
      if (p < 0) continue;
      const int d = dims_[v];
      std::vector<double>& bp = b[p];
      if (bp.empty()) bp.assign(static_cast<std::size_t>(d) * m, 0.0);
      for (int r = 0; r < rows; ++r)
        for (int t = 0; t < d; ++t)
          bp[t + static_cast<std::size_t>(row + r) * d] += lin.jacobians[k](r, t);
    }
    row += rows;
  }
  // The reach: every position on the paths to the root, ascending.
  std::vector<int> reach;
  std::vector<char> seen(chol_.size(), 0);
  for (const auto& entry : b)
    for (int p = entry.first; p >= 0 && !seen[p]; p = chol_.parent(p)) {
      seen[p] = 1;
      reach.push_back(p);
    }
  std::sort(reach.begin(), reach.end());
  g->setZero(m, m);
  for (int p : reach) {
    const int d = chol_.dim(p);
    std::vector<double>& z = b[p];
    if (z.empty()) z.assign(static_cast<std::size_t>(d) * m, 0.0);
    const int nc = chol_.rowBlocks(p);
    const int* cols = chol_.rowInts(p);
    const int* offs = cols + nc;
    const double* vals = chol_.rowValues(p);
    solveUtX(vals + offs[0], z.data(), d, m);
    const Eigen::Map<const Eigen::MatrixXd> zp(z.data(), d, m);
    g->noalias() += zp.transpose() * zp;
    for (int k = 1; k < nc; ++k) {
      const int c = cols[k];
      const int dc = chol_.dim(c);
      std::vector<double>& bc = b[c];
      if (bc.empty()) bc.assign(static_cast<std::size_t>(dc) * m, 0.0);
      const Eigen::Map<const Eigen::MatrixXd> rpc(vals + offs[k], d, dc);
      Eigen::Map<Eigen::MatrixXd>(bc.data(), dc, m).noalias() -= rpc.transpose() * zp;
    }
    z.clear();
    z.shrink_to_fit();
  }
  return true;
}

bool AprilSamBackend::reweighFactors(UpdateResult* result) {
  // Each reweighted factor out at the weight R holds and in at its new one,
  // at the same linearisation point: the difference of H and A^T b.
  for (int f : reweighted_) {
    if (weight_[f] == lin_weight_[f]) continue;
    if (!linearizeFactor(f, -1.0, false, result) || !linearizeFactor(f, 1.0, false, result))
      return false;
  }
  reweighted_.clear();
  return true;
}

UpdateCosts AprilSamBackend::updateCosts(double incremental) const {
  UpdateCosts costs;
  costs.incremental = incremental;
  costs.batch = last_batch_cost_;
  costs.possible_loop_closure_nodes = countPossibleLoopClosureNodes();
  return costs;
}

bool AprilSamBackend::dormant(std::size_t f, int m) const {
  return m >= 0 && factors_[f]->modeInformationScale(m) < options_.dormant_scale;
}

bool AprilSamBackend::linearizeFactors(std::size_t begin, std::size_t end, bool as_rows,
                                       UpdateResult* result) {
  double cost = 0, largest = 0;
  for (std::size_t f = begin; f < end; ++f) {
    if (!linearizeFactor(f, 1.0, as_rows, result)) return false;
    cost += lin_scratch_.cost;
    largest = std::max(largest, lin_scratch_.cost);
  }
  if (!std::isfinite(cost)) {
    // Each factor is finite, their sum is not: the system cannot be trusted.
    const std::vector<FactorPtr> factors(factors_.begin() + begin, factors_.begin() + end);
    result->status = finiteCostStatus(cost, factors, estimate_, "aprilsam");
    return false;
  }
  if (largest > kMaxResolvableChi2) {
    // A residual whose rounding alone exceeds one standard deviation: no
    // step computed from it resolves the estimate (finite_result.h).
    const std::vector<FactorPtr> factors(factors_.begin() + begin, factors_.begin() + end);
    result->status = resolvableCostStatus(factors, estimate_, "aprilsam");
    if (!result->status.ok()) return false;
  }
  return true;
}

bool AprilSamBackend::estimateIsFinite(UpdateResult* result) {
  changed_keys_.clear();
  bool finite = true;
  for (int p : solve_.changed()) {
    const int v = var_at_[p];
    changed_keys_.push_back(keys_[v]);
    for (int t = 0; t < dims_[v]; ++t) finite &= std::isfinite(est_[v][t]);
  }
  // The estimate is read through est_ (no hash lookup per key, which cost a
  // batch as much as its solve); the Status that names the variable is
  // built only on a failure, or for an empty change set, where it checks all.
  if (finite && !changed_keys_.empty()) {
    result->status = Status();
    return true;
  }
  result->status = finiteEstimateStatus(estimate_, "aprilsam", changed_keys_);
  return result->status.ok();
}

void AprilSamBackend::relinearizeSwitchedModes(UpdateResult* result) {
  if (!any_modes_ || broken_) return;
  constexpr int kMaxPasses = 4;
  std::vector<int> switched, vars, touched;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    // Only variables whose estimate changed can have changed a mode.
    ++stamp_;
    switched.clear();
    bool all_raised = true;
    for (int p : solve_.changed()) {
      for (int f : moded_of_var_[var_at_[p]]) {
        if (factor_stamp_[f] == stamp_) continue;
        factor_stamp_[f] = stamp_;
        const int b = factor_begin_[f], e = factor_begin_[f + 1];
        params_.resize(e - b);
        for (int k = b; k < e; ++k) params_[k - b] = est_[factor_vars_[k]];
        const int m = factors_[f]->mode(params_.data());
        if (m == lin_mode_[f]) continue;
        switched.push_back(f);
        all_raised &= null_pair_[f] && lin_mode_[f] == 1 && m == 0;
      }
    }
    if (switched.empty()) return;

    if (all_raised) {
      // Every switch is a nominal + null pair turning nominal: its nominal
      // component is added at the linearisation point R holds it at, as
      // rows (addRows) like a new factor's, instead of relinearising its
      // variables and every factor on them and refactoring R from there.
      long rows = 0;
      for (int f : switched) rows += nominalComponent(f)->residualDim();
      const bool as_rows = options_.factor_update == AprilSamOptions::FactorUpdate::kRank &&
                           rows <= options_.rank_update_max_rows;
      rows_.clear();
      neq_.clear(chol_.size());
      for (int f : switched)
        if (!raiseToNominal(f, as_rows, result)) {
          broken_ = true;
          return;
        }
      std::ostringstream why;
      why << "; " << switched.size() << " factor(s) switched mode: nominal rows added";
      result->reason += why.str();
      if (!solveAfterSwitch(as_rows ? chol_.addRows(rows_) : chol_.update(neq_, false), result))
        return;
      continue;
    }

    // The switched factors' free variables move their linearisation point
    // to the estimate; every factor on them is relinearised.
    ++stamp_;
    vars.clear();
    touched.clear();
    for (int f : switched)
      for (int k = factor_begin_[f]; k < factor_begin_[f + 1]; ++k) {
        const int v = factor_vars_[k];
        if (fixed_[v] || var_stamp_[v] == stamp_) continue;
        var_stamp_[v] = stamp_;
        vars.push_back(v);
        for (int g : factors_of_var_[v])
          if (factor_stamp_[g] != stamp_) {
            factor_stamp_[g] = stamp_;
            touched.push_back(g);
          }
      }
    neq_.clear(chol_.size());
    for (int f : touched)
      if (!linearizeFactor(f, -1.0, false, result)) {
        broken_ = true;
        return;
      }
    for (int v : vars)
      for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
    for (int f : touched)
      if (!linearizeFactor(f, 1.0, false, result)) {
        broken_ = true;
        return;
      }
    result->variables_relinearized += vars.size();
    std::ostringstream why;
    why << "; " << switched.size() << " factor(s) switched mode: " << vars.size()
        << " variable(s) relinearised";
    result->reason += why.str();
    if (!solveAfterSwitch(chol_.update(neq_, false), result)) return;
  }
}

// After a switch pass changed R: the new estimate, or, when R lost positive
// definiteness, a damped batch (false: the pass is over).
bool AprilSamBackend::solveAfterSwitch(const IncrementalCholesky::Outcome& out,
                                       UpdateResult* result) {
  if (!out.ok) {
    batchUpdate(result->reason + "; not positive definite at " +
                    keys_[var_at_[out.failed_position]].str() + ": damped batch",
                true, result);
    return false;
  }
  result->columns_recomputed += out.columns_recomputed;
  solve_.solve(chol_, options_.backsolve == AprilSamOptions::Backsolve::kFull,
               options_.backsolve_tol);
  applyChangedDx();
  return true;
}

// estimate = lin_point [+] dx for the variables whose dx changed, and the
// bookkeeping of L and ||dx|| that the update policy reads.
void AprilSamBackend::applyChangedDx() {
  for (int p : solve_.changed()) {
    const int v = var_at_[p];
    const double* dx = solve_.dx(p);
    const int d = dims_[v];
    double sq = 0, inf = 0;
    for (int t = 0; t < d; ++t) {
      sq += dx[t] * dx[t];
      inf = std::max(inf, std::fabs(dx[t]));
      est_[v][t] = lin_[v].data[t] + dx[t];
    }
    // Values::retract's convention: plain addition, Pose2 angle wrapped.
    if (lin_[v].type == VariableType::kPose2) est_[v][2] = wrapAngle(est_[v][2]);
    dx_sq_ += sq - dx_sq_of_[v];
    dx_sq_of_[v] = sq;
    const char m = !(inf < options_.policy.delta_t);  // NaN counts as moved
    moved_count_ += m - moved_[v];
    moved_[v] = m;
  }
}

std::vector<int> AprilSamBackend::computeOrdering() {
  const int n = static_cast<int>(keys_.size());
  if (options_.ordering == AprilSamOptions::Ordering::kNatural) {
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    return order;
  }
  OrderingInput& in = ordering_input_;
  in.positions.resize(n);
  for (int v = 0; v < n; ++v) in.positions[v] = orderingPosition(v);
  in.newest = newest_pose_;
  if (!moded_factors_.empty()) {
    // The factors with modes that are not dormant at the linearisation
    // points (batchUpdate has just moved them) join a copy of the graph.
    moded_ordering_input_ = in;
    dormant_count_ = 0;
    for (int f : moded_factors_) {
      const int b = factor_begin_[f], e = factor_begin_[f + 1];
      params_.resize(e - b);
      for (int k = b; k < e; ++k) params_[k - b] = lin_[factor_vars_[k]].data.data();
      // The batch's linearisation reads this mode back (modes_at_lin_known_)
      // rather than evaluating every mixture a second time.
      lin_mode_[f] = factors_[f]->mode(params_.data());
      if (dormant(f, lin_mode_[f])) {
        ++dormant_count_;
        continue;
      }
      for (int i = b; i < e; ++i)
        for (int j = i + 1; j < e; ++j)
          moded_ordering_input_.adjacency[factor_vars_[i]].push_back(factor_vars_[j]);
    }
    modes_at_lin_known_ = true;
    if (options_.ordering == AprilSamOptions::Ordering::kMinHeap)
      return minHeapOrdering(moded_ordering_input_, options_.loop_closure_radius,
                             &ordering_workspace_);
    if (options_.ordering == AprilSamOptions::Ordering::kBhamd)
      return bhamdOrdering(moded_ordering_input_);
    return amdOrdering(moded_ordering_input_);
  }
  if (options_.ordering == AprilSamOptions::Ordering::kMinHeap)
    return minHeapOrdering(in, options_.loop_closure_radius, &ordering_workspace_);
  if (options_.ordering == AprilSamOptions::Ordering::kBhamd) return bhamdOrdering(in);
  return amdOrdering(in);
}

bool AprilSamBackend::reeliminateTop(const std::string& reason, UpdateResult* result) {
  if (any_modes_ || damped_ || broken_) return false;
  Stopwatch sw;
  const int n = static_cast<int>(keys_.size());
  const int m = chol_.size();
  std::vector<int> path, relin;
  for (std::size_t f = factors_at_top_; f < factors_.size(); ++f)
    for (int k = factor_begin_[f]; k < factor_begin_[f + 1]; ++k)
      if (pos_of_[factor_vars_[k]] >= 0) path.push_back(pos_of_[factor_vars_[k]]);
  // L, and the variables on their way to it: one that settles just below
  // delta_T would otherwise never be relinearised (a full batch moves every
  // variable, so AprilSAM's batches do not meet this).
  const double relin_sq = std::pow(options_.top_relinearize * options_.policy.delta_t, 2);
  for (int v = 0; v < n; ++v)
    if (pos_of_[v] >= 0 && (moved_[v] || dx_sq_of_[v] >= relin_sq)) relin.push_back(pos_of_[v]);
  const std::vector<int> top = chol_.topOf(path, relin);
  const int nt = static_cast<int>(top.size());
  if (nt == 0 || nt > options_.top_share * m) return false;

  // The factors on the top; one that also reaches a kept row holds the
  // top variables it touches at their linearisation points (the kept row
  // has it linearised there).
  std::vector<int> local(n, -1);  // v -> index in top
  for (int k = 0; k < nt; ++k) local[var_at_[top[k]]] = k;
  ++stamp_;
  std::vector<int> fs;
  std::vector<char> pinned(nt, 0);
  for (int p : top) {
    for (int f : factors_of_var_[var_at_[p]]) {
      if (factor_stamp_[f] == stamp_) continue;
      factor_stamp_[f] = stamp_;
      fs.push_back(f);
      bool straddles = false;
      for (int k = factor_begin_[f]; k < factor_begin_[f + 1]; ++k) {
        const int u = factor_vars_[k];
        straddles |= pos_of_[u] >= 0 && local[u] < 0;
      }
      if (!straddles) continue;
      for (int k = factor_begin_[f]; k < factor_begin_[f + 1]; ++k)
        if (local[factor_vars_[k]] >= 0) pinned[local[factor_vars_[k]]] = 1;
    }
  }
  long relinearized = 0;
  for (int k = 0; k < nt; ++k) {
    if (pinned[k]) continue;
    const int v = var_at_[top[k]];
    for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
    ++relinearized;
  }
  result->time.other += sw.lap();

  // The top's graph: its factors, and the separator of each kept subtree
  // hanging from the top as a clique (the marginal it leaves there). A
  // row's structure holds its children's but for the parent itself, so the
  // subtree's root row (its parent in the top) has the whole separator.
  OrderingInput in;
  in.adjacency.assign(nt, {});
  in.positions.resize(nt);
  for (int k = 0; k < nt; ++k) in.positions[k] = orderingPosition(var_at_[top[k]]);
  in.newest = newest_pose_ >= 0 ? local[newest_pose_] : -1;
  for (int f : fs)
    for (int i = factor_begin_[f]; i < factor_begin_[f + 1]; ++i)
      for (int j = i + 1; j < factor_begin_[f + 1]; ++j) {
        const int a = local[factor_vars_[i]], b = local[factor_vars_[j]];
        if (a >= 0 && b >= 0) in.adjacency[a].push_back(b);
      }
  std::vector<int> sep;
  for (int p = 0; p < m; ++p) {
    const int parent = chol_.parent(p);
    if (local[var_at_[p]] >= 0 || parent < 0 || local[var_at_[parent]] < 0) continue;
    const IncrementalCholesky::Row r = chol_.row(p);
    sep.clear();
    for (std::size_t k = 1; k < r.cols.size(); ++k) {
      const int l = local[var_at_[r.cols[k]]];
      if (l >= 0) sep.push_back(l);
    }
    for (std::size_t i = 0; i < sep.size(); ++i)
      for (std::size_t j = i + 1; j < sep.size(); ++j) in.adjacency[sep[i]].push_back(sep[j]);
  }
  const std::vector<int> local_order =
      minHeapOrdering(in, options_.loop_closure_radius, &ordering_workspace_);
  std::vector<int> order(nt), rank(nt);
  for (int k = 0; k < nt; ++k) {
    order[k] = top[local_order[k]];
    rank[local_order[k]] = k;
  }
  result->time.order += sw.lap();

  // H on the top at its new positions (after the m - nt kept rows), the
  // kept variables at none (their blocks dropped, as a fixed variable's).
  for (int f : fs)
    for (int k = factor_begin_[f]; k < factor_begin_[f + 1]; ++k) {
      const int u = factor_vars_[k];
      pos_of_[u] = local[u] >= 0 ? m - nt + rank[local[u]] : -1;
    }
  neq_.clear(m);
  double cost = 0;
  bool ok = true;
  for (int f : fs) {
    if (!(ok = linearizeFactor(f, 1.0, false, result))) break;
    cost += lin_scratch_.cost;
  }
  for (int p = 0; p < m; ++p) pos_of_[var_at_[p]] = p;
  if (!ok || !std::isfinite(cost)) {
    result->status = Status();
    return false;
  }
  result->time.linearize += sw.lap();

  std::vector<int> new_pos;
  const IncrementalCholesky::Outcome out = chol_.reorderTop(top, order, neq_, &new_pos);
  result->time.factor += sw.lap();
  if (!out.ok) return false;  // the batch that follows rebuilds R
  const std::vector<int> old_var_at = var_at_;
  for (int p = 0; p < m; ++p) {
    var_at_[new_pos[p]] = old_var_at[p];
    pos_of_[old_var_at[p]] = new_pos[p];
  }
  // Every row is solved, as after a batch: the partial solves' tolerance
  // (backsolve_tol) has let dx drift by up to that much per row since the
  // last full solve, and with few batches nothing else would correct it
  // (on city10000 the drift alone leaves the final chi2 well outside 1e-4
  // of the optimum). The kept rows' dx move to their new positions first,
  // so that the changed set is what the re-elimination changed.
  solve_.permute(new_pos);
  solve_.solve(chol_, true, 0.0);
  applyChangedDx();
  if (!estimateIsFinite(result)) {
    broken_ = true;
    return true;
  }
  result->time.solve += sw.lap();
  factors_at_top_ = factors_.size();
  // The time criterion weighs the increments against a batch of R as it is
  // now; the last full batch's R may be far smaller.
  if (options_.policy.cost == UpdatePolicyOptions::Cost::kDeterministic)
    last_batch_cost_ = chol_.totalFlops();
  result->kind = UpdateKind::kIncremental;
  result->reason = reason + "; top re-eliminated: " + std::to_string(nt) + " of " +
                   std::to_string(m) + " rows, " + std::to_string(relinearized) +
                   " variables relinearised";
  result->columns_recomputed += out.columns_recomputed;
  result->variables_relinearized = relinearized;
  return true;
}

void AprilSamBackend::batchOrTop(const std::string& reason, UpdateResult* result) {
  if (options_.reeliminate == AprilSamOptions::Reeliminate::kTop && reeliminateTop(reason, result))
    return;
  batchUpdate(reason, false, result);
  relinearizeSwitchedModes(result);
}

void AprilSamBackend::batchUpdate(const std::string& reason, bool damped, UpdateResult* result) {
  Stopwatch total, sw;
  const int n = static_cast<int>(keys_.size());
  result->kind = UpdateKind::kBatch;
  result->reason = reason;
  // Alg. 3.1 line 13: every linearisation point moves to the estimate.
  for (int v = 0; v < n; ++v)
    for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
  result->variables_relinearized = n;
  result->time.other += sw.lap();

  // Fixed variables have no position: the order holds the free ones.
  std::vector<int> order;
  order.reserve(n);
  for (int v : computeOrdering())
    if (!fixed_[v]) order.push_back(v);
  const int m = static_cast<int>(order.size());
  var_at_ = order;
  std::fill(pos_of_.begin(), pos_of_.end(), -1);
  for (int k = 0; k < m; ++k) pos_of_[order[k]] = k;
  std::vector<int> dims(m);
  for (int k = 0; k < m; ++k) dims[k] = dims_[order[k]];
  result->time.order += sw.lap();

  double lambda = options_.damping;
  for (long it = 0; it < options_.batch_iterations; ++it) {
    neq_.clear(m);
    const bool linearized = linearizeFactors(0, factors_.size(), false, result);
    modes_at_lin_known_ = false;
    if (linearized) reweighted_.clear();  // every factor is in at its weight now
    if (!linearized) {
      broken_ = true;
      return;
    }
    result->time.linearize += sw.lap();
    chol_.reset(dims);
    if (damped) neq_.damp(lambda, 1e-9);
    IncrementalCholesky::Outcome out = chol_.update(neq_, true);
    for (int attempt = 0; !out.ok && attempt < 6; ++attempt) {
      const Key bad = keys_[var_at_[out.failed_position]];
      if (!damped) {
        result->reason += "; batch not positive definite at " + bad.str() + ": damped";
        damped = true;
      } else {
        lambda *= 10;
      }
      // damp() adds, so the total damping is the sum of the steps.
      neq_.damp(lambda, 1e-9);
      out = chol_.update(neq_, true);
    }
    result->time.factor += sw.lap();
    if (!out.ok) {
      const Key bad = keys_[var_at_[out.failed_position]];
      result->status = Status::numericalFailure(
          "aprilsam: the normal equations are not positive definite at " + bad.str() +
              " even with damping (is the variable constrained?)",
          {bad});
      broken_ = true;
      chol_.reset(dims);
      solve_.reset(m);
      return;
    }
    result->columns_recomputed += out.columns_recomputed;
    solve_.reset(m);
    solve_.solve(chol_, true, 0.0);
    dx_sq_ = 0;
    moved_count_ = 0;
    std::fill(dx_sq_of_.begin(), dx_sq_of_.end(), 0.0);
    std::fill(moved_.begin(), moved_.end(), 0);
    applyChangedDx();
    if (!estimateIsFinite(result)) {
      broken_ = true;
      return;
    }
    if (it + 1 < options_.batch_iterations) {
      for (int v = 0; v < n; ++v)
        for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
    }
    result->time.solve += sw.lap();
  }
  result->iterations = static_cast<int>(options_.batch_iterations);
  broken_ = false;
  for (auto& cell : grid_) cell.second.clear();  // keep the cells' capacity
  for (int v = 0; v < n; ++v) gridInsert(v);
  ++batches_;
  damped_ = damped;
  factors_at_top_ = factors_.size();
  last_batch_cost_ = options_.policy.cost == UpdatePolicyOptions::Cost::kWallclock
                         ? total.seconds()
                         : chol_.totalFlops();
  result->time.other += sw.lap();
}

UpdateResult AprilSamBackend::update(const Step& step) {
  UpdateResult result;
  Stopwatch sw;

  // The one input contract (core/step.h): bad input throws before anything
  // is recorded and leaves the back-end as it was.
  checkStep(step, estimate_, "aprilsam");
  const std::vector<Key> new_keys = step.new_values.keys();
  const std::unordered_set<Key> new_fixed(step.fixed.begin(), step.fixed.end());

  // Alg. 3.1 line 2, AugmentGraph: new variables at the end of the order; a
  // fixed one keeps its value and gets no position (core/step.h).
  for (const Key& key : new_keys) {
    const Values::Entry& e = step.new_values.entry(key);
    const int v = static_cast<int>(keys_.size());
    const bool fixed = new_fixed.count(key) > 0;
    index_.emplace(key, v);
    keys_.push_back(key);
    dims_.push_back(dimension(e.type));
    fixed_.push_back(fixed);
    lin_.push_back(e);
    estimate_.insertEntry(key, e);
    est_.push_back(estimate_.data(key));
    moved_.push_back(0);
    dx_sq_of_.push_back(0);
    if (fixed) {
      pos_of_.push_back(-1);
    } else {
      pos_of_.push_back(chol_.size());
      var_at_.push_back(v);
      chol_.append(dims_.back());
      solve_.append();
    }
    ordering_input_.adjacency.emplace_back();
    if (e.type == VariableType::kPose2) newest_pose_ = v;
    gridInsert(v);
  }
  // A known variable fixed now loses its column: R has to be rebuilt
  // without it, which a batch does.
  bool refixed = false;
  for (const Key& key : step.fixed) {
    const int v = index_.at(key);
    if (fixed_[v]) continue;
    fixed_[v] = 1;
    for (int t = 0; t < dims_[v]; ++t) lin_[v].data[t] = est_[v][t];
    refixed = true;
  }
  const std::size_t first_new = factors_.size();
  factors_of_var_.resize(keys_.size());
  moded_of_var_.resize(keys_.size());
  var_stamp_.resize(keys_.size(), 0);
  for (const FactorPtr& f : step.new_factors) {
    const int b = static_cast<int>(factor_vars_.size());
    const int index = static_cast<int>(factors_.size());
    const bool moded = f->hasModes();
    any_modes_ |= moded;
    for (const Key& key : f->keys()) {
      const int v = index_.at(key);
      factor_vars_.push_back(v);
      factors_of_var_[v].push_back(index);
      if (moded) moded_of_var_[v].push_back(index);
    }
    const int e = static_cast<int>(factor_vars_.size());
    factors_.push_back(f);
    weight_.push_back(1);
    lin_weight_.push_back(1);
    factor_index_.emplace(f.get(), index);
    factor_begin_.push_back(e);
    lin_mode_.push_back(0);
    held_nominal_.push_back(0);
    {
      const auto* mixture = moded ? dynamic_cast<const MaxMixtureFactor*>(f.get()) : nullptr;
      null_pair_.push_back(mixture && mixture->isNullHypothesisPair());
    }
    factor_stamp_.push_back(0);
    if (moded) {
      moded_factors_.push_back(index);  // its edges join each batch's ordering graph
      continue;
    }
    for (int i = b; i < e; ++i)  // one-sided lists: the orderings symmetrise
      for (int j = i + 1; j < e; ++j)
        ordering_input_.adjacency[factor_vars_[i]].push_back(factor_vars_[j]);
  }
  result.time.other += sw.lap();

  if (broken_) {
    batchUpdate("the previous batch failed", false, &result);
    relinearizeSwitchedModes(&result);
  } else if (refixed) {
    batchUpdate("a known variable was fixed", false, &result);
    relinearizeSwitchedModes(&result);
  } else if (steps_ == 0) {
    // The first update is always a batch (UpdatePolicy): there is no order
    // yet, and an incremental pass in arrival order would only add fill.
    batchUpdate("first update", false, &result);
    relinearizeSwitchedModes(&result);
  } else {
    // Alg. 3.1 lines 3-4: the incremental update (eq. 3.14, 3.19) and the
    // back-substitution.
    long new_rows = 0;
    for (const FactorPtr& f : step.new_factors) new_rows += f->residualDim();
    // Reweighted factors take weight out as well as in: not a rank update.
    const bool as_rows = options_.factor_update == AprilSamOptions::FactorUpdate::kRank &&
                         new_rows <= options_.rank_update_max_rows && reweighted_.empty();
    neq_.clear(chol_.size());
    rows_.clear();
    if (!linearizeFactors(first_new, factors_.size(), as_rows, &result) ||
        !reweighFactors(&result)) {
      result.variables = keys_.size();
      result.columns_total = chol_.columnsTotal();
      return result;
    }
    result.time.linearize += sw.lap();
    if (options_.batch_first && as_rows &&
        options_.policy.cost == UpdatePolicyOptions::Cost::kDeterministic) {
      // batch_first: the criteria that do not read the step's solve (the
      // cost one, with the flops the rank update would report, and the
      // periodic one) are asked first; when they call for a batch, the rank
      // update and its solve are not run, and the batch starts from the
      // estimate before them (the new variables at their guesses).
      const UpdateDecision early =
          policy_.decide(steps_, 0, 0.0, updateCosts(chol_.addRowsFlops(rows_)));
      result.time.other += sw.lap();
      if (early.batch) {
        // With reeliminate=top the step's new factors enter the top's H in
        // full (every variable they touch is in the top), so the top, like
        // a batch, needs no rank update before it.
        batchOrTop(early.reason, &result);
        ++steps_;
        result.variables = keys_.size();
        result.columns_total = chol_.columnsTotal();
        return result;
      }
    }
    const IncrementalCholesky::Outcome out =
        as_rows ? chol_.addRows(rows_) : chol_.update(neq_, false);

    result.time.factor += sw.lap();
    if (!out.ok) {
      batchUpdate("incremental update not positive definite at " +
                      keys_[var_at_[out.failed_position]].str() + ": damped batch",
                  true, &result);
      relinearizeSwitchedModes(&result);
    } else {
      solve_.solve(chol_, options_.backsolve == AprilSamOptions::Backsolve::kFull,
                   options_.backsolve_tol);
      applyChangedDx();
      result.time.solve += sw.lap();
      result.kind = UpdateKind::kIncremental;
      result.columns_recomputed = out.columns_recomputed;
      if (!estimateIsFinite(&result)) {
        // Back to the linearisation points, which are finite; the next
        // update is a batch from there.
        for (Key k : changed_keys_) {
          const int v = index_.at(k);
          std::copy(lin_[v].data.begin(), lin_[v].data.begin() + dims_[v], est_[v]);
        }
        broken_ = true;
        ++steps_;
        result.variables = keys_.size();
        result.columns_total = chol_.columnsTotal();
        return result;
      }
      // Alg. 3.1 lines 5-11: the batch decision.
      const auto decide = [&] {
        const double incremental =
            options_.policy.cost == UpdatePolicyOptions::Cost::kWallclock
                ? result.time.linearize + result.time.factor + result.time.solve
                : out.flops;
        return policy_.decide(steps_, moved_count_, std::sqrt(std::max(dx_sq_, 0.0)),
                              updateCosts(incremental));
      };
      // A batch relinearises every variable and checks every mode after its
      // solve, so switch passes before it would be refactored away: they
      // run only when the step stays incremental, and the decision is taken
      // again after them (they move the estimate, so |L| and ||dx||).
      UpdateDecision decision = decide();
      result.time.other += sw.lap();
      if (!decision.batch) {
        relinearizeSwitchedModes(&result);
        result.time.factor += sw.lap();
        if (result.kind == UpdateKind::kIncremental) decision = decide();
        result.time.other += sw.lap();
      }
      if (decision.batch) {
        batchOrTop(decision.reason, &result);
      } else {
        result.reason = decision.reason + result.reason;
      }
    }
  }
  ++steps_;
  result.variables = keys_.size();
  result.columns_total = chol_.columnsTotal();
  return result;
}

}  // namespace hamal::aprilsam
