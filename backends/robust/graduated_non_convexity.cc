// GraduatedNonConvexity: see graduated_non_convexity.h.
#include "backends/robust/graduated_non_convexity.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>
#include <sstream>

#include "backends/robust/answer_doubt.h"
#include "backends/robust/consistent_group.h"
#include "backends/robust/rebuilt_factor_weights.h"
#include "backends/robust/truncated_objective_check.h"
#include "core/error.h"
#include "core/multi_modal.h"

namespace hamal::robust {

namespace {

std::string num(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

}  // namespace

std::vector<OptionSpec> GncOptions::optionSpecs() {
  const GncOptions d;
  return {
      {"gnc_probability", num(d.inlier_probability),
       "GNC: the inlier threshold c2 is the chi2 quantile of a candidate's residual dimension at "
       "this probability (GTSAM's GncOptimizer default)"},
      {"gnc_threshold", "0", "GNC: c2 itself, in chi2 units, when > 0 (overrides gnc_probability)"},
      {"gnc_mu_step", num(d.mu_step),
       "GNC: factor of each mu update (TLS: mu *= step; GM: mu /= step down to 1)"},
      {"gnc_max_iterations", std::to_string(d.max_iterations),
       "GNC: outer iterations per update before the status is not_converged"},
      {"gnc_weight_tolerance", num(d.weight_tolerance),
       "GNC-TLS: converged when every annealed weight is this close to 0 or 1"},
      {"gnc_linear_limit", std::to_string(d.linear_limit),
       "GNC: at most this many candidates of a step are annealed on the back-end's "
       "factorisation (first order, then checked); 0: one weighted solve per outer iteration"},
      {"gnc_cost_tolerance", num(d.cost_tolerance),
       "GNC: converged when the annealed candidates' weighted cost changes by less than this "
       "(relative)"},
      {"gnc_doubt", "adopt",
       "GNC: an answer in doubt (backends/robust/README.md) is: off (not checked), report "
       "(status uncertain), adopt (a cheaper alternative is taken, then checked again)"},
      {"gnc_closing", "report",
       "GNC: at the end of a run a cheaper alternative is: report (status uncertain), adopt "
       "(with gnc_doubt=adopt: taken, then checked again; backends/robust/DOUBT.md)"},
      {"gnc_group", "off",
       "GNC: on: an answer in doubt is also checked against least squares over the largest "
       "set of closures the odometry says agree (PCM's clique), and the closing verdict covers "
       "every closure (backends/robust/DOUBT.md)"},
      {"gnc_noise_scale", "adopt",
       "GNC: at the end of a run the noise scale's alternative (backends/robust/NOISE_SCALE.md) "
       "is: report (status uncertain), adopt (with gnc_doubt=adopt: taken and checked again, a "
       "plain alternative then judged at the scaled c2 too)"},
  };
}

GncOptions GncOptions::fromOptions(const Options& o, Loss loss) {
  GncOptions g;
  g.loss = loss;
  const std::string who = o.owner().empty() ? "gnc" : o.owner();
  g.inlier_probability = o.getDouble("gnc_probability");
  g.inlier_threshold = o.getDouble("gnc_threshold");
  g.mu_step = o.getDouble("gnc_mu_step");
  g.max_iterations = o.getInt("gnc_max_iterations");
  g.weight_tolerance = o.getDouble("gnc_weight_tolerance");
  g.cost_tolerance = o.getDouble("gnc_cost_tolerance");
  g.linear_limit = o.getInt("gnc_linear_limit");
  const std::string& doubt = o.getString("gnc_doubt");
  if (doubt == "off")
    g.doubt = GncOptions::Doubt::kOff;
  else if (doubt == "report")
    g.doubt = GncOptions::Doubt::kReport;
  else if (doubt == "adopt")
    g.doubt = GncOptions::Doubt::kAdopt;
  else
    throw Error(who + ": option gnc_doubt must be off, report or adopt, not '" + doubt + "'");
  const auto reportOrAdopt = [&](const std::string& name) {
    const std::string& v = o.getString(name);
    if (v == "report") return GncOptions::Doubt::kReport;
    if (v == "adopt") return GncOptions::Doubt::kAdopt;
    throw Error(who + ": option " + name + " must be report or adopt, not '" + v + "'");
  };
  g.closing = reportOrAdopt("gnc_closing");
  g.noise_scale = reportOrAdopt("gnc_noise_scale");
  const std::string& group = o.getString("gnc_group");
  if (group != "on" && group != "off")
    throw Error(who + ": option gnc_group must be on or off, not '" + group + "'");
  g.consistent_group = group == "on";
  if (g.linear_limit < 0) throw Error(who + ": option gnc_linear_limit must be >= 0");
  if (!(g.inlier_probability > 0 && g.inlier_probability < 1))
    throw Error(who + ": option gnc_probability must be in (0, 1)");
  if (!(g.inlier_threshold >= 0) || !std::isfinite(g.inlier_threshold))
    throw Error(who +
                ": option gnc_threshold must be a finite number >= 0 (0: use gnc_probability)");
  if (!(g.mu_step > 1) || !std::isfinite(g.mu_step))
    throw Error(who + ": option gnc_mu_step must be a finite number > 1");
  if (g.max_iterations < 1) throw Error(who + ": option gnc_max_iterations must be >= 1");
  if (!(g.weight_tolerance > 0 && g.weight_tolerance < 0.5))
    throw Error(who + ": option gnc_weight_tolerance must be in (0, 0.5)");
  if (!(g.cost_tolerance >= 0) || !std::isfinite(g.cost_tolerance))
    throw Error(who + ": option gnc_cost_tolerance must be a finite number >= 0");
  return g;
}

double gncWeight(GncOptions::Loss loss, double s, double mu, double c2) {
  if (loss == GncOptions::Loss::kGemanMcClure) {
    const double a = mu * c2;
    return (a / (s + a)) * (a / (s + a));
  }
  if (s >= (mu + 1) / mu * c2) return 0;
  if (s <= mu / (mu + 1) * c2) return 1;
  return std::clamp(std::sqrt(c2 * mu * (mu + 1) / s) - mu, 0.0, 1.0);
}

double gncInitialMu(GncOptions::Loss loss, double s_max, double c2) {
  if (loss == GncOptions::Loss::kGemanMcClure) return 2 * s_max / c2;
  // Remark 5 of the paper; <= 0 when no residual is large enough to need
  // the truncation (every candidate an inlier), and bounded below as GTSAM
  // does for residuals far beyond c2.
  if (!(2 * s_max - c2 > 0)) return -1;
  return std::max(c2 / (2 * s_max - c2), 1e-6);
}

double gncNextMu(GncOptions::Loss loss, double mu, double mu_step) {
  if (loss == GncOptions::Loss::kGemanMcClure) return std::max(1.0, mu / mu_step);
  return mu * mu_step;
}

double chiSquareQuantile(int dof, double p) {
  if (dof < 1) throw Error("chi2 quantile: " + std::to_string(dof) + " degrees of freedom");
  if (!(p > 0 && p < 1)) throw Error("chi2 quantile: probability " + num(p) + " is not in (0, 1)");
  return boost::math::quantile(boost::math::chi_squared(dof), p);
}

GraduatedNonConvexity::GraduatedNonConvexity(std::function<std::unique_ptr<Backend>()> make,
                                             Predicate is_candidate, GncOptions options)
    : make_(std::move(make)), is_candidate_(std::move(is_candidate)), options_(options) {
  inner_ = make_();
  if (!inner_) throw Error("gnc: the inner back-end could not be made");
  weights_ = dynamic_cast<FactorWeights*>(inner_.get());
  native_weights_ = weights_ != nullptr;
  if (!weights_) {
    auto rebuilt = std::make_unique<RebuiltFactorWeights>(make_, std::move(inner_));
    weights_ = rebuilt.get();
    inner_ = std::move(rebuilt);
  }
}

GraduatedNonConvexity::~GraduatedNonConvexity() = default;

const Values& GraduatedNonConvexity::estimate() const { return inner_->estimate(); }

double GncOptions::threshold(int dim) const {
  if (inlier_threshold > 0) return inlier_threshold;
  return chiSquareQuantile(dim, inlier_probability);
}

double GraduatedNonConvexity::threshold(const Factor& factor) const {
  return options_.threshold(factor.residualDim());
}

bool GraduatedNonConvexity::rejected(double weight) const {
  return options_.loss == GncOptions::Loss::kGemanMcClure ? weight < 0.25 : weight < 0.5;
}

std::vector<GraduatedNonConvexity::Decision> GraduatedNonConvexity::decisions() const {
  std::vector<Decision> out;
  out.reserve(candidates_.size());
  for (const Candidate& c : candidates_) out.push_back({c.factor, c.weight, c.chi2});
  return out;
}

bool GraduatedNonConvexity::evaluate(std::size_t i) {
  Candidate& c = candidates_[i];
  const Values& est = inner_->estimate();
  if (c.endpoints.empty()) {
    for (const Key& k : c.factor->keys()) {
      c.endpoints.push_back(est.data(k));
      c.dims.push_back(est.dim(k));
    }
    c.seen.assign(c.endpoints.size() * 3, std::numeric_limits<double>::quiet_NaN());
  }
  for (std::size_t k = 0; k < c.endpoints.size(); ++k)
    for (int t = 0; t < c.dims[k]; ++t) c.seen[3 * k + t] = c.endpoints[k][t];
  c.chi2 = c.factor->chi2(est);
  return std::isfinite(c.chi2);
}

void GraduatedNonConvexity::setWeight(std::size_t i, double w) {
  Candidate& c = candidates_[i];
  if (c.weight == w || !c.held) return;
  weights_->setFactorWeight(c.factor, w);
  c.weight = w;
}

bool GraduatedNonConvexity::evaluateAll(const std::vector<std::size_t>& set, UpdateResult* result) {
  for (std::size_t i : set)
    if (!evaluate(i)) {
      result->status = Status::numericalFailure(
          "gnc: a candidate does not evaluate to a finite chi2 at the estimate",
          candidates_[i].factor->keys());
      return false;
    }
  return true;
}

bool GraduatedNonConvexity::commit(const std::vector<std::size_t>& set,
                                   const std::vector<double>& w, UpdateResult* result) {
  Step add;
  std::vector<std::size_t> added;
  for (std::size_t k = 0; k < set.size(); ++k) {
    Candidate& c = candidates_[set[k]];
    if (c.held) {
      setWeight(set[k], w[k]);
    } else if (w[k] > 0) {
      add.new_factors.push_back(c.keep);
      c.held = true;
      c.weight = 1;
      added.push_back(k);
    }
  }
  if (!solve(result, add)) return false;
  bool again = false;
  for (std::size_t k : added)
    if (w[k] != 1) {
      setWeight(set[k], w[k]);
      again = true;
    }
  return !again || solve(result);
}

bool GraduatedNonConvexity::solve(UpdateResult* result, const Step& step) {
  Step indexed = step;
  indexed.index = steps_;
  const UpdateResult r = inner_->update(indexed);
  if (r.kind == UpdateKind::kBatch) result->kind = UpdateKind::kBatch;
  result->iterations += r.iterations;
  result->variables = r.variables;
  result->variables_relinearized += r.variables_relinearized;
  result->columns_recomputed += r.columns_recomputed;
  result->columns_total = r.columns_total;
  result->time.linearize += r.time.linearize;
  result->time.order += r.time.order;
  result->time.factor += r.time.factor;
  result->time.solve += r.time.solve;
  result->time.other += r.time.other;
  result->time.estimate += r.time.estimate;
  // A weighted solve that stops at its iteration limit is still a warm
  // start for the next one (GTSAM's GNC goes on the same way); what the last
  // one said is the update's status.
  result->status = r.status;
  return r.status.code != Status::kNumericalFailure;
}

std::vector<std::size_t> GraduatedNonConvexity::revisit(std::size_t first_new) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < first_new; ++i) {
    Candidate& c = candidates_[i];
    bool moved = false;
    for (std::size_t k = 0; k < c.endpoints.size() && !moved; ++k)
      for (int t = 0; t < c.dims[k]; ++t) moved |= c.seen[3 * k + t] != c.endpoints[k][t];
    if (!moved || !evaluate(i)) continue;
    if (c.held) {
      if (rejected(c.weight) != (c.chi2 > c.c2)) out.push_back(i);
    } else if (c.chi2 <= kRevisitMargin * c.c2 || c.chi2 <= 0.5 * c.checked_chi2) {
      out.push_back(i);
    }
  }
  return out;
}

double GraduatedNonConvexity::initialMu(const std::vector<std::size_t>& set,
                                        const std::vector<double>& chi2) const {
  // GTSAM's rule with each candidate's own c2: the smallest TLS mu, the
  // largest GM mu, that keeps every term convex.
  const GncOptions::Loss loss = options_.loss;
  double mu = loss == GncOptions::Loss::kGemanMcClure ? 0 : std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < set.size(); ++k) {
    const double m = gncInitialMu(loss, chi2[k], candidates_[set[k]].c2);
    if (loss == GncOptions::Loss::kGemanMcClure)
      mu = std::max(mu, m);
    else if (m > 0)
      mu = std::min(mu, m);
  }
  return mu;
}

bool GraduatedNonConvexity::converged(double mu, bool binary, double cost, double prev_cost) const {
  const bool by_mu =
      options_.loss == GncOptions::Loss::kGemanMcClure ? std::abs(mu - 1) < 1e-9 : binary;
  return by_mu ||
         (std::isfinite(prev_cost) &&
          std::abs(cost - prev_cost) <= options_.cost_tolerance * std::max(prev_cost, 1e-7));
}

void GraduatedNonConvexity::notConverged(std::size_t candidates, long iterations,
                                         UpdateResult* result) const {
  result->status.code = Status::kNotConverged;
  result->status.message = "gnc: the weights of " + std::to_string(candidates) +
                           " candidate(s) did not converge in " + std::to_string(iterations) +
                           " outer iterations (gnc_max_iterations)";
}

void GraduatedNonConvexity::anneal(const std::vector<std::size_t>& set, UpdateResult* result) {
  last_iterations_ = 0;
  if (set.empty()) return;
  const long n = static_cast<long>(set.size());
  if (options_.loss == GncOptions::Loss::kTruncatedLeastSquares && steps_ > 1 &&
      options_.linear_limit > 0 && n > options_.linear_limit) {
    // Incremental TLS with many candidates (old ones revisited when a loop
    // moves the map): block by block on the factorisation, the step's new
    // ones (last in `set`) first, each block a descent of the same
    // objective.
    std::vector<std::size_t> order(set.rbegin(), set.rend());
    long iterations = 0;
    for (std::size_t b = 0; b < order.size(); b += kBlock) {
      const std::vector<std::size_t> block(order.begin() + b,
                                           order.begin() + std::min(order.size(), b + kBlock));
      annealBlock(block, result);
      iterations += last_iterations_;
      if (result->status.code == Status::kNumericalFailure) break;
    }
    last_iterations_ = iterations;
    return;
  }
  annealBlock(set, result);
}

void GraduatedNonConvexity::annealBlock(const std::vector<std::size_t>& set, UpdateResult* result) {
  if (static_cast<long>(set.size()) <= options_.linear_limit && annealLinear(set, result)) return;
  // From the least-squares start: every candidate of the set in the
  // back-end at weight 1.
  bool reset = false;
  for (std::size_t i : set) reset |= candidates_[i].weight != 1 || !candidates_[i].held;
  if (reset) {
    if (!commit(set, std::vector<double>(set.size(), 1.0), result)) return;
    if (!evaluateAll(set, result)) return;
  }
  annealIterative(set, result);
}

int GraduatedNonConvexity::stack(const std::vector<std::size_t>& set,
                                 std::vector<const Factor*>* factors,
                                 std::vector<int>* offset) const {
  int m = offset->empty() ? 0 : offset->back() + factors->back()->residualDim();
  for (std::size_t i : set) {
    factors->push_back(candidates_[i].factor);
    offset->push_back(m);
    m += candidates_[i].factor->residualDim();
  }
  return m;
}

double linearisedCostChange(const Eigen::MatrixXd& g, const Eigen::VectorXd& r,
                            const Eigen::VectorXd& d) {
  std::vector<int> rows;
  for (int i = 0; i < d.size(); ++i)
    if (d[i] != 0) rows.push_back(i);
  if (rows.empty()) return 0;
  const int n = static_cast<int>(rows.size());
  Eigen::MatrixXd a(n, n);
  Eigen::VectorXd rs(n), ds(n);
  for (int i = 0; i < n; ++i) {
    rs[i] = r[rows[i]];
    ds[i] = d[rows[i]];
    for (int j = 0; j < n; ++j) a(i, j) = (i == j) + g(rows[i], rows[j]) * d[rows[j]];
  }
  const Eigen::VectorXd y = a.partialPivLu().solve(rs);
  return rs.dot(ds.cwiseProduct(y));
}

std::vector<std::size_t> GraduatedNonConvexity::withTentative(std::vector<std::size_t> set,
                                                              Eigen::MatrixXd* g_set) {
  bool fresh = false;
  for (std::size_t i : set) fresh |= !candidates_[i].held;
  if (!fresh || tentative_.empty() || set.size() >= kExactLimit) return set;
  std::vector<std::size_t> pool;
  for (auto it = tentative_.rbegin(); it != tentative_.rend() && pool.size() < kTentativePool; ++it)
    if (std::find(set.begin(), set.end(), *it) == set.end()) pool.push_back(*it);
  if (pool.empty()) return set;
  std::vector<const Factor*> factors;
  std::vector<int> offset;
  stack(set, &factors, &offset);
  const int m = stack(pool, &factors, &offset);
  Eigen::MatrixXd g;
  if (!weights_->residualCovariance(factors, &g) || g.rows() != m || !g.allFinite()) return set;
  Eigen::VectorXd r(m);
  const Values& est = inner_->estimate();
  for (std::size_t k = 0; k < factors.size(); ++k)
    if (!factors[k]->evaluate(est, r.data() + offset[k])) return set;
  const auto index = [&](std::size_t k) { return k < set.size() ? set[k] : pool[k - set.size()]; };
  // The linearised TLS cost of moving the weights of candidates `ks` to `to`.
  const auto cost = [&](const std::vector<std::size_t>& ks, const std::vector<double>& to) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(m);
    double penalty = 0;
    for (std::size_t i = 0; i < ks.size(); ++i) {
      const Candidate& c = candidates_[index(ks[i])];
      penalty += (c.weight - to[i]) * c.c2;
      d.segment(offset[ks[i]], factors[ks[i]]->residualDim()).setConstant(to[i] - c.weight);
    }
    return linearisedCostChange(g, r, d) + penalty;
  };
  // A tentative closure joins when letting it go and taking a new
  // candidate in costs less than the best the new candidate can do alone.
  std::vector<std::pair<double, std::size_t>> ranked;
  for (std::size_t p = 0; p < pool.size(); ++p) {
    const std::size_t a = set.size() + p;
    double gain = 0;
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (candidates_[set[k]].held) continue;
      const double alone = std::min(cost({k}, {0.0}), cost({k}, {1.0}));
      gain = std::max(gain, alone - cost({k, a}, {1.0, 0.0}));
    }
    if (gain > 0) ranked.push_back({gain, pool[p]});
  }
  std::sort(ranked.rbegin(), ranked.rend());
  // G of the returned set is a block of this one: its rows, in its order.
  std::vector<int> rows;
  const auto take = [&](std::size_t k) {
    for (int t = 0; t < factors[k]->residualDim(); ++t) rows.push_back(offset[k] + t);
  };
  const std::size_t asked = set.size();
  for (std::size_t k = 0; k < asked; ++k) take(k);
  for (const auto& [rho, i] : ranked) {
    if (set.size() >= kExactLimit) break;
    set.push_back(i);
    take(asked + (std::find(pool.begin(), pool.end(), i) - pool.begin()));
  }
  *g_set = g(rows, rows);
  return set;
}

void GraduatedNonConvexity::markTentative(const std::vector<std::size_t>& set,
                                          const std::vector<double>& w, const Eigen::MatrixXd& g,
                                          const std::vector<int>& offset) {
  for (std::size_t k = 0; k < set.size(); ++k) {
    const Candidate& c = candidates_[set[k]];
    const int dim = c.factor->residualDim();
    bool tentative = false;
    if (!rejected(w[k])) {
      // The map's own variance of the residual, in units of the closure's:
      // the eigenvalues of G for a closure not held, of G (I - G)^-1 (from
      // its leverage) for one held. A closure is unverified when the map
      // could bend to fit it in all but one direction (an information
      // matrix near singular gives every closure one such direction).
      const Eigen::MatrixXd gk = g.block(offset[k], offset[k], dim, dim);
      Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gk).eigenvalues();
      if (c.held)
        for (int i = 0; i < dim; ++i)
          ev[i] = ev[i] >= 1 ? std::numeric_limits<double>::infinity() : ev[i] / (1 - ev[i]);
      const double variance = ev[std::max(0, dim - 2)];  // ascending: the second largest
      tentative = variance > kTentativeVariance;
    }
    const auto at = std::find(tentative_.begin(), tentative_.end(), set[k]);
    if (tentative && at == tentative_.end()) tentative_.push_back(set[k]);
    if (!tentative && at != tentative_.end()) tentative_.erase(at);
  }
}

bool GraduatedNonConvexity::annealLinear(std::vector<std::size_t> set, UpdateResult* result) {
  const GncOptions::Loss loss = options_.loss;
  const bool tls = loss == GncOptions::Loss::kTruncatedLeastSquares;
  Eigen::MatrixXd g_first;  // G of the set at this linearisation, when withTentative has it
  if (tls) set = withTentative(std::move(set), &g_first);
  std::vector<const Factor*> factors;
  std::vector<int> offset;
  const int m = stack(set, &factors, &offset);
  long it = 0;
  // TLS: a few rounds, each deciding on the model at the back-end's latest
  // linearisation point, until the decision holds (the model of the first
  // round can be far off where rotations change much).
  // A held closure the decision lets go was judged by the model's
  // (I - G)^-1, which blows up where the closure holds a direction alone
  // (a tight closure: its leverage, the largest eigenvalue of its block of
  // G, above kAloneLeverage) and then turns a residual a little above c2,
  // left by a stale linearisation or a tolerant back substitution, into a
  // vast predicted gain. So such a release is reopened:
  // the next round, at the relinearised map, judges it as a closure not
  // held, through (I + G)^-1, which stays bounded; taken back in, it stays
  // for the rest of the call. Not so a tentative closure, whose release is
  // the replacement the tentative pool is for: alone it fits anywhere.
  std::vector<char> reopened(set.size(), 0), confirmed(set.size(), 0);
  int rounds = tls ? kLinearRounds : 1;
  for (int round = 0; round < rounds; ++round) {
    Eigen::MatrixXd g;
    if (round == 0 && g_first.rows() == m)
      g = std::move(g_first);
    else if (!weights_->residualCovariance(factors, &g) || g.rows() != m || !g.allFinite())
      return round > 0;
    Eigen::VectorXd r(m), w0(m), d(m);
    const Values& est = inner_->estimate();
    std::vector<double> w(set.size()), now(set.size());
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (!factors[k]->evaluate(est, r.data() + offset[k])) return round > 0;
      now[k] = candidates_[set[k]].weight;
      w0.segment(offset[k], factors[k]->residualDim()).setConstant(now[k]);
    }
    const auto rowsOf = [&](const std::vector<double>& x) {
      for (std::size_t k = 0; k < set.size(); ++k)
        d.segment(offset[k], factors[k]->residualDim()).setConstant(x[k]);
      return d - w0;
    };
    // The residuals at weights x, to first order.
    const auto moveTo = [&](const std::vector<double>& x, Eigen::VectorXd* out) {
      const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(m, m) + g * rowsOf(x).asDiagonal();
      *out = a.partialPivLu().solve(r);
      return out->allFinite();
    };
    bool reopen = false;
    if (tls) {
      // A held candidate within c2 stays: letting it go could lower the
      // cost only through the model's (I - G)^-1, which is least reliable
      // exactly where such a factor holds a direction alone. Tentative
      // closures are the exception, to be replaced by later ones.
      std::vector<bool> locked(set.size());
      for (std::size_t k = 0; k < set.size(); ++k) {
        const Candidate& c = candidates_[set[k]];
        locked[k] = confirmed[k] ||
                    (c.held && c.weight == 1 &&
                     r.segment(offset[k], c.factor->residualDim()).squaredNorm() <= c.c2 &&
                     std::find(tentative_.begin(), tentative_.end(), set[k]) == tentative_.end());
      }
      const auto objective = [&](const std::vector<double>& x) {
        for (std::size_t k = 0; k < set.size(); ++k)
          if (locked[k] && x[k] != 1) return std::numeric_limits<double>::infinity();
        double penalty = 0;
        for (std::size_t k = 0; k < set.size(); ++k) penalty += (1 - x[k]) * candidates_[set[k]].c2;
        return linearisedCostChange(g, r, rowsOf(x)) + penalty;
      };
      it += decideTruncated(set, offset, moveTo, objective, locked, &w);
      // Taken back in by the second opinion: judged where it counts, so
      // not one to give way to the next candidate.
      std::vector<std::size_t> taken_back;
      for (std::size_t k = 0; k < set.size(); ++k)
        if (reopened[k] && w[k] == 1) {
          confirmed[k] = 1;
          taken_back.push_back(set[k]);
        }
      // This round's releases of closures that hold a direction alone (the
      // tentative status read before markTentative changes it).
      for (std::size_t k = 0; k < set.size(); ++k) {
        const Candidate& c = candidates_[set[k]];
        const int dim = c.factor->residualDim();
        reopened[k] = c.held && now[k] == 1 && w[k] == 0 &&
                      std::find(tentative_.begin(), tentative_.end(), set[k]) == tentative_.end() &&
                      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
                          g.block(offset[k], offset[k], dim, dim), Eigen::EigenvaluesOnly)
                              .eigenvalues()
                              .maxCoeff() > kAloneLeverage;
        reopen |= reopened[k] != 0;
      }
      markTentative(set, w, g, offset);
      for (std::size_t i : taken_back)
        tentative_.erase(std::remove(tentative_.begin(), tentative_.end(), i), tentative_.end());
    } else {
      const long n = annealOnModel(set, offset, moveTo, &w);
      if (n < 0) return false;
      it += n;
    }
    bool changes = false;
    for (std::size_t k = 0; k < set.size(); ++k) {
      changes |= w[k] != now[k];
      if (!candidates_[set[k]].held) candidates_[set[k]].checked_chi2 = candidates_[set[k]].chi2;
    }
    if (!changes) break;
    if (!commit(set, w, result)) return true;  // a numerical failure is the update's status
    const auto holds = [&] {
      bool all = true;
      for (std::size_t k = 0; k < set.size(); ++k) {
        Candidate& c = candidates_[set[k]];
        if (!evaluate(set[k])) return false;
        if (!c.held) c.checked_chi2 = c.chi2;
        all &= rejected(c.weight) || c.chi2 <= c.c2;
      }
      return all;
    };
    bool held = holds();
    // One update is one Gauss-Newton step from where the map was; a closure
    // that pulls it far needs a few before its residual says anything.
    // The first of them relinearises where the back-end keeps old
    // linearisations: rows built at a point the loop has moved away from
    // answer another problem, and the residual would judge that one.
    for (int settle = 0; tls && (!held || (reopen && settle == 0)) && settle < kSettleSolves;
         ++settle) {
      if (settle == 0) weights_->relinearizeAtNextUpdate(factors);
      if (!solve(result)) return true;
      held = holds();
    }
    if (held && !reopen) break;
    if (!tls) return false;
    if (reopen && round + 1 == rounds && rounds == kLinearRounds) ++rounds;
  }
  last_iterations_ = it;
  total_iterations_ += it;
  std::ostringstream why;
  why << "; gnc: " << it << " outer iteration(s) on the factorisation for " << set.size()
      << " candidate(s)";
  result->reason += why.str();
  return true;
}

long GraduatedNonConvexity::decideTruncated(
    const std::vector<std::size_t>& set, const std::vector<int>& offset, const MoveTo& moveTo,
    const std::function<double(const std::vector<double>&)>& objective,
    const std::vector<bool>& locked, std::vector<double>* w) {
  const std::size_t n = set.size();
  if (n <= kExactLimit) {
    // Every subset: the linearised TLS problem of the set, solved exactly.
    double best = std::numeric_limits<double>::infinity();
    std::vector<double> x(n);
    for (unsigned long mask = (1ul << n); mask-- > 0;) {
      for (std::size_t k = 0; k < n; ++k) x[k] = (mask >> k) & 1u;
      const double f = objective(x);
      if (f < best) {
        best = f;
        *w = x;
      }
    }
    return 1;
  }
  // GNC's schedule on the model, then single flips while they lower the
  // objective: a local minimum of the same problem.
  long it = annealOnModel(set, offset, moveTo, w);
  if (it < 0) w->assign(n, 1.0);
  it = std::max(it, 0L);
  for (std::size_t k = 0; k < n; ++k) (*w)[k] = locked[k] || (*w)[k] >= 0.5 ? 1.0 : 0.0;
  double f = objective(*w);
  for (std::size_t pass = 0; pass < 2 * n; ++pass) {
    std::size_t flip = n;
    for (std::size_t k = 0; k < n; ++k) {
      (*w)[k] = 1 - (*w)[k];
      const double fk = objective(*w);
      if (fk < f) {
        f = fk;
        flip = k;
      }
      (*w)[k] = 1 - (*w)[k];
    }
    if (flip == n) break;
    (*w)[flip] = 1 - (*w)[flip];
  }
  return it;
}

long GraduatedNonConvexity::annealOnModel(const std::vector<std::size_t>& set,
                                          const std::vector<int>& offset, const MoveTo& moveTo,
                                          std::vector<double>* w) {
  const GncOptions::Loss loss = options_.loss;
  const auto chi2Of = [&](const Eigen::VectorXd& v, std::size_t k) {
    return v.segment(offset[k], candidates_[set[k]].factor->residualDim()).squaredNorm();
  };
  // The least-squares start: every candidate of the set at weight 1.
  w->assign(set.size(), 1.0);
  std::vector<double> chi2(set.size());
  Eigen::VectorXd moved;
  if (!moveTo(*w, &moved)) return -1;
  for (std::size_t k = 0; k < set.size(); ++k) chi2[k] = chi2Of(moved, k);
  double mu = initialMu(set, chi2);
  long it = 0;
  if (loss == GncOptions::Loss::kGemanMcClure || std::isfinite(mu)) {
    double prev_cost = std::numeric_limits<double>::infinity();
    bool done = false;
    for (; it < options_.max_iterations && !done; ++it) {
      bool binary = true;
      for (std::size_t k = 0; k < set.size(); ++k) {
        (*w)[k] = gncWeight(loss, chi2[k], mu, candidates_[set[k]].c2);
        binary &= (*w)[k] <= options_.weight_tolerance || (*w)[k] >= 1 - options_.weight_tolerance;
      }
      if (!moveTo(*w, &moved)) return -1;
      double cost = 0;
      for (std::size_t k = 0; k < set.size(); ++k) {
        chi2[k] = chi2Of(moved, k);
        cost += (*w)[k] * chi2[k];
      }
      done = converged(mu, binary, cost, prev_cost);
      mu = gncNextMu(loss, mu, options_.mu_step);
      prev_cost = cost;
    }
    if (!done) return -1;
  }
  return it;
}

void GraduatedNonConvexity::annealIterative(const std::vector<std::size_t>& set,
                                            UpdateResult* result) {
  const GncOptions::Loss loss = options_.loss;
  std::vector<double> chi2;
  for (std::size_t i : set) chi2.push_back(candidates_[i].chi2);
  double mu = initialMu(set, chi2);
  if (loss == GncOptions::Loss::kTruncatedLeastSquares && !std::isfinite(mu)) return;

  double prev_cost = std::numeric_limits<double>::infinity();
  bool done = false;
  long it = 0;
  for (; it < options_.max_iterations && !done; ++it) {
    bool binary = true;
    for (std::size_t i : set) {
      const double w = gncWeight(loss, candidates_[i].chi2, mu, candidates_[i].c2);
      binary &= w <= options_.weight_tolerance || w >= 1 - options_.weight_tolerance;
      setWeight(i, w);
    }
    if (!solve(result)) {
      ++it;
      break;
    }
    double cost = 0;
    for (std::size_t i : set) {
      if (!evaluate(i)) {
        result->status = Status::numericalFailure(
            "gnc: a candidate does not evaluate to a finite chi2 at the estimate",
            candidates_[i].factor->keys());
        break;
      }
      cost += candidates_[i].weight * candidates_[i].chi2;
    }
    if (result->status.code == Status::kNumericalFailure) {
      ++it;
      break;
    }
    done = converged(mu, binary, cost, prev_cost);
    mu = gncNextMu(loss, mu, options_.mu_step);
    prev_cost = cost;
  }
  last_iterations_ = it;
  total_iterations_ += it;
  std::ostringstream why;
  why << "; gnc: " << it << " outer iteration(s) on " << set.size() << " candidate(s)";
  result->reason += why.str();
  if (result->status.code != Status::kNumericalFailure && !done)
    notConverged(set.size(), it, result);
}

UpdateResult GraduatedNonConvexity::update(const Step& step) {
  // Candidates are checked before the inner back-end sees the step, so a
  // refused one leaves everything as it was.
  std::vector<FactorPtr> fresh, inliers;
  for (const FactorPtr& f : step.new_factors) {
    if (!f) continue;
    if (!is_candidate_(*f)) {
      inliers.push_back(f);
      continue;
    }
    if (f->lossFunction())
      throw Error("gnc: candidate " + f->tag() + " on " + f->keys()[0].str() + "-" +
                  f->keys().back().str() + " carries a robust loss of its own");
    if (asMultiModal(*f))
      throw Error("gnc: candidate " + f->tag() + " on " + f->keys()[0].str() + "-" +
                  f->keys().back().str() + " has modes (a max-mixture): GNC weighs plain factors");
    fresh.push_back(f);
  }
  // With G at hand, the new candidates wait outside the back-end until
  // their weights are known (docs/ROBUST_RULES.md), except, for TLS, those already
  // within c2 / 2 at the estimate: the least-squares start can only bring
  // them closer, so GNC would keep them at weight 1 without annealing.
  Eigen::MatrixXd probe;
  const bool linear = steps_ > 0 && !fresh.empty() &&
                      static_cast<long>(fresh.size()) <= options_.linear_limit &&
                      weights_->residualCovariance({}, &probe);
  std::vector<double> c2;
  for (const FactorPtr& f : fresh) c2.push_back(threshold(*f));
  std::vector<FactorPtr> deferred;
  if (linear)
    for (std::size_t k = 0; k < fresh.size(); ++k) {
      const FactorPtr& f = fresh[k];
      if (options_.loss == GncOptions::Loss::kTruncatedLeastSquares) {
        Values ends;
        for (const Key& key : f->keys())
          ends.insertEntry(key, step.new_values.contains(key) ? step.new_values.entry(key)
                                                              : inner_->estimate().entry(key));
        if (f->chi2(ends) <= c2[k] / 2) continue;
      }
      deferred.push_back(f);
    }
  const auto isDeferred = [&](const FactorPtr& f) {
    return std::find(deferred.begin(), deferred.end(), f) != deferred.end();
  };
  UpdateResult result;
  if (!deferred.empty()) {
    Step without = step;
    without.new_factors.clear();
    for (const FactorPtr& f : step.new_factors)
      if (!isDeferred(f)) without.new_factors.push_back(f);
    result = inner_->update(without);
  } else {
    result = inner_->update(step);
  }
  ++steps_;
  if (closing_check_) closing_check_->add(step);
  inliers_.insert(inliers_.end(), inliers.begin(), inliers.end());
  fixed_.insert(fixed_.end(), step.fixed.begin(), step.fixed.end());
  const std::size_t first_new = candidates_.size();
  for (std::size_t k = 0; k < fresh.size(); ++k) {
    const FactorPtr& f = fresh[k];
    Candidate c;
    c.factor = f.get();
    c.keep = f;
    c.c2 = c2[k];
    c.held = !isDeferred(f);
    c.weight = c.held ? 1 : 0;
    candidates_.push_back(std::move(c));
  }
  last_iterations_ = 0;
  if (result.status.code == Status::kNumericalFailure) return result;

  std::vector<std::size_t> set = revisit(first_new);
  // New candidates that went straight in are decided already.
  std::vector<std::size_t> straight_in;
  for (std::size_t i = first_new; i < candidates_.size(); ++i)
    (!linear || !candidates_[i].held ? set : straight_in).push_back(i);
  if (!evaluateAll(set, &result) || !evaluateAll(straight_in, &result)) return result;
  anneal(set, &result);
  if (result.status.ok() && options_.doubt != GncOptions::Doubt::kOff) judge(&result);
  countFlips();
  return result;
}

void GraduatedNonConvexity::countFlips() {
  for (Candidate& c : candidates_) {
    const bool r = !c.held || rejected(c.weight);
    if (r != c.was_rejected) ++c.flips;
    c.was_rejected = r;
  }
}

double GraduatedNonConvexity::objective(const Values& at) const {
  std::vector<const Factor*> all;
  std::vector<double> c2;
  for (const Candidate& c : candidates_) {
    all.push_back(c.factor);
    c2.push_back(c.c2);
  }
  return truncatedObjective(inliers_, all, c2, at);
}

std::optional<Values> polishedGncSolve(const std::function<std::unique_ptr<Backend>()>& make,
                                       const std::function<bool(const Factor&)>& is_candidate,
                                       GncOptions options, const Step& problem,
                                       const std::vector<FactorPtr>& inliers,
                                       const std::vector<FactorPtr>& candidates,
                                       const std::vector<double>& c2, std::vector<double>* fits) {
  options.doubt = GncOptions::Doubt::kOff;
  GraduatedNonConvexity nested(make, is_candidate, options);
  if (nested.update(problem).status.code == Status::kNumericalFailure) return std::nullopt;
  Values at = nested.estimate();
  for (int round = 0; round < kPolishSolves; ++round) {
    Step fit;
    fit.new_values = at;
    fit.fixed = problem.fixed;
    fit.new_factors = inliers;
    fits->assign(candidates.size(), 0);
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (candidates[i]->chi2(at) <= c2[i]) {
        (*fits)[i] = 1;
        fit.new_factors.push_back(candidates[i]);
      }
    const std::unique_ptr<Backend> solver = make();
    if (solver->update(fit).status.code == Status::kNumericalFailure) return std::nullopt;
    at = solver->estimate();
  }
  return at;
}

bool GraduatedNonConvexity::alternative(double* objective, std::vector<double>* w,
                                        bool in_doubt) const {
  std::vector<FactorPtr> keep;
  std::vector<const Factor*> all;
  std::vector<double> c2;
  std::vector<std::size_t> rejected_now, recent;
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    const Candidate& c = candidates_[i];
    if (!c.held || rejected(c.weight)) {
      rejected_now.push_back(i);
      if (i >= recent_from_) recent.push_back(i);
    }
    keep.push_back(c.keep);
    all.push_back(c.factor);
    c2.push_back(c.c2);
  }
  // GNC from the answer over `group` (inliers and those rejected closures),
  // polished over every closure; false when it cannot be made.
  const auto solve = [&](const std::vector<std::size_t>& group,
                         const std::function<std::unique_ptr<Backend>()>& make, double* theirs,
                         std::vector<double>* fits, bool trusted = false) {
    // A trusted group is solved in least squares (c2 out of reach), as
    // PCM would keep it; the polish then judges each closure at c2.
    GncOptions options = options_;
    if (trusted) options.inlier_threshold = std::numeric_limits<double>::max();
    Step batch;
    batch.new_values = inner_->estimate();
    batch.fixed = fixed_;
    batch.new_factors = inliers_;
    for (std::size_t i : group) batch.new_factors.push_back(candidates_[i].keep);
    try {
      const std::optional<Values> at =
          polishedGncSolve(make, is_candidate_, options, batch, inliers_, keep, c2, fits);
      if (!at) return false;
      *theirs = truncatedObjective(inliers_, all, c2, *at);
    } catch (const Error&) {
      return false;  // an alternative that does not evaluate is no evidence either way
    }
    return true;
  };
  const bool made = solve(rejected_now, make_, objective, w);
  // The rejected closures that came since the check before, as a group of
  // their own: a revisit after a long drift brings true closures that were
  // each rejected alone on the drifted map, and GNC's least-squares start
  // over them and many earlier false ones is bent by those (as riSAM
  // anneals a step's affected closures together). Solved on the
  // alternatives' back-end (setAlternativeMaker: more Gauss-Newton steps
  // from that far start), and taken only where it keeps every closure the
  // answer accepts: a map that drops accepted closures for the truncated
  // objective is what the default c2 prefers where it is wrong (the
  // tuning worlds, backends/robust/DOUBT.md).
  // Only where most of the closures since the check before were rejected
  // (kMaxRejectedShare of them, the share rule's line): a revisit rejected
  // on a drifted map looks so; where most were accepted the recent group
  // is the false ones among them, and solving it costs a batch for nothing.
  bool any = made;
  const auto take = [&](double theirs, std::vector<double>* fits) {
    if (any && *objective <= theirs) return;
    any = true;
    *objective = theirs;
    *w = std::move(*fits);
  };
  const std::size_t arrived = candidates_.size() - std::min(recent_from_, candidates_.size());
  if (make_alternative_ && !recent.empty() && recent.size() != rejected_now.size() &&
      static_cast<double>(recent.size()) > kMaxRejectedShare * static_cast<double>(arrived)) {
    double theirs = 0;
    std::vector<double> fits;
    if (solve(recent, make_alternative_, &theirs, &fits) && dropsOfAdoption(fits) == 0)
      take(theirs, &fits);
  }
  // The consistent group (gnc_group=on), only for an answer in doubt: an
  // answer no rule doubts keeps its decisions, since where the stated noise
  // is overstated (intel) the group's map fits false closures within c2
  // and is cheaper than a right answer. It keeps every accepted closure, as
  // the recent group does.
  if (options_.consistent_group && in_doubt) {
    const std::vector<bool> in = consistentGroup(inliers_, all, kGroupCliqueSeconds);
    std::vector<std::size_t> group;
    bool adds = false;
    for (std::size_t i = 0; i < in.size(); ++i)
      if (in[i]) {
        group.push_back(i);
        adds |= !candidates_[i].held || rejected(candidates_[i].weight);
      }
    double theirs = 0;
    std::vector<double> fits;
    if (group.size() >= 2 && adds &&
        solve(group, make_alternative_ ? make_alternative_ : make_, &theirs, &fits, true) &&
        dropsOfAdoption(fits) == 0)
      take(theirs, &fits);
  }
  return any;
}

std::size_t GraduatedNonConvexity::dropsOfAdoption(const std::vector<double>& w) const {
  std::size_t drops = 0;
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    const Candidate& c = candidates_[i];
    drops += c.held && !rejected(c.weight) && w[i] < 0.5;
  }
  return drops;
}

long GraduatedNonConvexity::alternativesChecked() const {
  return alternatives_checked_ + (closing_check_ ? closing_check_->checks() : 0);
}

void GraduatedNonConvexity::setAlternativeMaker(std::function<std::unique_ptr<Backend>()> make) {
  make_alternative_ = std::move(make);
}

void GraduatedNonConvexity::setClosingCheck(std::unique_ptr<TruncatedObjectiveCheck> check) {
  if (steps_ > 0) throw Error("gnc: a closing check is set before the first update");
  closing_check_ = std::move(check);
}

Status GraduatedNonConvexity::innerClosingVerdict() {
  if (auto* inner = dynamic_cast<ClosingVerdict*>(inner_.get())) return inner->closingVerdict();
  return Status();
}

Status GraduatedNonConvexity::closingVerdict() {
  // The inner back-end's own first (AprilSAM's full back-substitution):
  // the rules judge the answer it ends with.
  if (const Status s = innerClosingVerdict(); !s.ok()) return s;
  if (options_.doubt == GncOptions::Doubt::kOff) return Status();
  Status own;
  if (options_.consistent_group) {
    own = catchUpVerdict();
    if (own.code == Status::kNumericalFailure) return own;
    if (!closing_check_) return own.ok() ? own : Status::uncertain("gnc: " + own.message);
  }
  if (!closing_check_) return ownClosingVerdict();
  // The check replaces the own rule here: its maker picks starts the own
  // one does not try (robust_loop_closures.cc).
  closing_check_->weighNearMisses(weights_);
  Status doubt = closing_check_->judge(inner_->estimate(), true);
  const long adopted = alternatives_adopted_;
  // Each alternative was cheaper by its rule's margin already.
  if (!doubt.ok() && closingAdopts())
    if (const std::optional<Values> cheaper = closing_check_->takeCheaperMap())
      if (!adoptClosingMap(*cheaper, &doubt)) return doubt;
  if (!doubt.ok() && noiseScaleAdopts())
    if (const std::optional<Values> cheaper = closing_check_->takeNoiseScaleMap())
      if (!adoptClosingMap(*cheaper, &doubt)) return doubt;
  // An adopted map was judged by every rule again: the catch-up's verdict
  // was on the answer before it.
  if (!own.ok() && alternatives_adopted_ == adopted)
    doubt = doubt.ok() ? own : Status::uncertain(own.message + "; " + doubt.message);
  return doubt.ok() ? doubt : Status::uncertain("gnc: " + doubt.message);
}

Status GraduatedNonConvexity::catchUpVerdict() {
  UpdateResult result;
  if (!checkWhenDue(candidates_.size() > checked_candidates_,
                    options_.doubt == GncOptions::Doubt::kAdopt, &result))
    return result.status;
  const Status doubt = decisionDoubt(alternative_status_, true);
  countFlips();
  return doubt;
}

bool GraduatedNonConvexity::adoptClosingMap(const Values& cheaper, Status* doubt) {
  // Adopt as an update would: the decisions the cheaper map makes (a
  // closure within its c2 there is in) go into the inner back-end, and the
  // answer they give is judged again by every rule.
  std::vector<double> w(candidates_.size());
  double mine = 0, theirs = 0;
  try {
    mine = objective();
    theirs = objective(cheaper);
    for (std::size_t i = 0; i < w.size(); ++i)
      w[i] = candidates_[i].factor->chi2(cheaper) <= candidates_[i].c2 ? 1 : 0;
  } catch (const Error&) {
    return true;  // no map to adopt: the doubt stands, reported
  }
  UpdateResult result;
  if (!adopt(w, mine, theirs, &result)) {
    *doubt = result.status;
    return false;
  }
  if (const Status s = innerClosingVerdict(); !s.ok()) {
    *doubt = s;
    return false;
  }
  *doubt = decisionDoubt(closing_check_->judgeAgain(inner_->estimate(), true), true);
  countFlips();
  return true;
}

Status GraduatedNonConvexity::ownClosingVerdict() {
  if (candidates_.size() <= checked_candidates_) return Status();
  const long adopted = alternatives_adopted_;
  UpdateResult result;
  if (!checkWhenDue(true, closingAdopts(), &result)) return result.status;
  if (alternatives_adopted_ == adopted)
    return alternative_status_.ok() ? Status()
                                    : Status::uncertain("gnc: " + alternative_status_.message);
  // An adopted answer is judged by every rule, as at an update.
  const Status doubt = decisionDoubt(alternative_status_, true);
  countFlips();
  return doubt.ok() ? doubt : Status::uncertain("gnc: " + doubt.message);
}

bool GraduatedNonConvexity::adopt(const std::vector<double>& w, double mine, double theirs,
                                  UpdateResult* result) {
  std::vector<std::size_t> all(candidates_.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  ++alternatives_adopted_;
  result->reason += "; gnc: adopted a cheaper alternative (truncated objective " + num(theirs) +
                    ", was " + num(mine) + ")";
  if (!commit(all, w, result)) return false;
  for (int k = 0; k < kSettleSolves; ++k)
    if (!solve(result)) return false;
  return evaluateAll(all, result);
}

bool GraduatedNonConvexity::checkAlternative(double margin, bool adopt_cheaper,
                                             UpdateResult* result) {
  alternative_status_ = Status();
  const int rounds = adopt_cheaper ? 2 : 1;
  for (int round = 0; round < rounds; ++round) {
    double mine = 0, theirs = 0;
    std::vector<double> w;
    try {
      mine = objective();
    } catch (const Error&) {
      break;
    }
    ++alternatives_checked_;
    const bool in_doubt = options_.consistent_group && !decisionDoubt(Status(), true).ok();
    if (!alternative(&theirs, &w, in_doubt)) break;
    alternative_status_ = alternativeDoubt(mine, theirs, margin);
    if (alternative_status_.ok() || round + 1 == rounds) break;
    // Adopt: the alternative's decisions go in, and are checked again.
    if (!adopt(w, mine, theirs, result)) return false;
    alternative_status_ = Status();
  }
  return true;
}

Status GraduatedNonConvexity::shareDoubt(std::size_t rejected_count, bool fresh) {
  const Status share = rejectedShareDoubt(rejected_count, candidates_.size());
  if (share.ok() || !weights_) return share;
  if (fresh || !refuted_at_ ||
      static_cast<double>(candidates_.size()) >= kRecheckGrowth * refuted_at_) {
    std::vector<const Factor*> out, in;
    std::vector<double> c2;
    for (const Candidate& c : candidates_) {
      if (c.held && !rejected(c.weight)) {
        in.push_back(c.factor);
        continue;
      }
      out.push_back(c.factor);
      c2.push_back(c.c2);
    }
    refuted_ = refutation(*weights_, out, c2, in, inner_->estimate());
    refuted_at_ = candidates_.size();
  }
  return rejectedShareDoubt(rejected_count, candidates_.size(), refuted_);
}

Status GraduatedNonConvexity::decisionDoubt(const Status& alternative, bool fresh) {
  std::size_t rejected_count = 0;
  std::vector<int> flips;
  for (const Candidate& c : candidates_) {
    const bool r = !c.held || rejected(c.weight);
    rejected_count += r;
    flips.push_back(c.flips + (r != c.was_rejected));
  }
  std::string why;
  for (const Status& s : {alternative, flipDoubt(flips), shareDoubt(rejected_count, fresh)})
    if (!s.ok()) why += (why.empty() ? "" : "; ") + s.message;
  return why.empty() ? Status() : Status::uncertain(why);
}

bool GraduatedNonConvexity::checkWhenDue(bool due, bool adopt_cheaper, UpdateResult* result) {
  std::size_t rejected_count = 0;
  double margin = std::numeric_limits<double>::infinity();
  for (const Candidate& c : candidates_) {
    rejected_count += !c.held || rejected(c.weight);
    margin = std::min(margin, c.c2);
  }
  if (rejected_count == 0) {
    alternative_status_ = Status();  // the alternative would be the answer itself
    return true;
  }
  if (!due) return true;
  recent_from_ = checked_candidates_;
  checked_candidates_ = candidates_.size();
  return checkAlternative(margin, adopt_cheaper, result);
}

void GraduatedNonConvexity::judge(UpdateResult* result) {
  const bool due = !candidates_.empty() &&
                   (checked_candidates_ == 0 || static_cast<double>(candidates_.size()) >=
                                                    kRecheckGrowth * checked_candidates_);
  if (!checkWhenDue(due, options_.doubt == GncOptions::Doubt::kAdopt, result)) return;
  const Status doubt = decisionDoubt(alternative_status_);
  if (!doubt.ok() && result->status.ok())
    result->status = Status::uncertain("gnc: " + doubt.message);
}

}  // namespace hamal::robust
