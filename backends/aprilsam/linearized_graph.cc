// LinearizedGraph: see linearized_graph.h (thesis sec. 3.3-3.4, Alg. 3.1).
#include "backends/aprilsam/linearized_graph.h"

#include <algorithm>
#include <cmath>

#include "core/finite_result.h"
#include "core/pose2.h"

namespace hamal::aprilsam {

namespace {
// A linearisation times a factor weight w: rows and residual by sqrt(w).
void scale(double w, Linearization* lin) {
  const double s = std::sqrt(w);
  lin->residual *= s;
  for (auto& j : lin->jacobians) j *= s;
  lin->cost *= w;
}
}  // namespace

int LinearizedGraph::addVariable(Key key, const Values::Entry& guess, bool is_fixed) {
  const int v = static_cast<int>(keys.size());
  index.emplace(key, v);
  keys.push_back(key);
  dims.push_back(dimension(guess.type));
  fixed.push_back(is_fixed);
  lin.push_back(guess);
  estimate.insertEntry(key, guess);
  est.push_back(estimate.data(key));
  moved.push_back(0);
  dx_sq_of.push_back(0);
  if (is_fixed) {
    pos_of.push_back(-1);
  } else {
    pos_of.push_back(chol.size());
    var_at.push_back(v);
    chol.append(dims.back());
    solve.append();
  }
  factors_of_var.emplace_back();
  modes.of_var.emplace_back();
  var_stamp.push_back(0);
  if (guess.type == VariableType::kPose2) newest_pose = v;
  return v;
}

int LinearizedGraph::addFactor(const FactorPtr& factor) {
  const int b = static_cast<int>(factor_vars.size());
  const int f = static_cast<int>(factors.size());
  for (const Key& key : factor->keys()) {
    const int v = index.at(key);
    factor_vars.push_back(v);
    factors_of_var[v].push_back(f);
  }
  const int e = static_cast<int>(factor_vars.size());
  factors.push_back(factor);
  weight.push_back(1);
  lin_weight.push_back(1);
  factor_index.emplace(factor.get(), f);
  factor_begin.push_back(e);
  factor_stamp.push_back(0);
  modes.add(f, *factor, factor_vars.data() + b, e - b);
  return f;
}

void LinearizedGraph::gatherEstimate(std::size_t f) {
  const int b = factor_begin[f], e = factor_begin[f + 1];
  params.resize(e - b);
  for (int k = b; k < e; ++k) params[k - b] = est[factor_vars[k]];
}

Eigen::Vector2d LinearizedGraph::orderingPosition(int v) const {
  // A non-finite location is put far away, so the min-heap's distance test
  // (eq. 3.20) neither reads NaN nor counts it near the newest pose.
  const Eigen::Vector2d p(lin[v].data[0], lin[v].data[1]);
  return p.allFinite() ? p : Eigen::Vector2d::Constant(1e300);
}

bool LinearizedGraph::gatherFactor(std::size_t f, bool at_lin_point) {
  const int b = factor_begin[f], e = factor_begin[f + 1];
  params.resize(e - b);
  fpos.resize(e - b);
  fdims.resize(e - b);
  bool touches_fixed = false;
  for (int k = b; k < e; ++k) {
    const int v = factor_vars[k];
    params[k - b] = at_lin_point ? lin[v].data.data() : est[v];
    fpos[k - b] = pos_of[v];
    fdims[k - b] = dims[v];
    touches_fixed |= pos_of[v] < 0;
  }
  return touches_fixed;
}

bool LinearizedGraph::linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                                        UpdateResult* result) {
  if (!linearize(factor, params.data(), &scratch)) {
    result->status = Status::numericalFailure(
        "aprilsam: a " + factors[f]->tag() +
            " factor does not evaluate to finite numbers at the linearisation point",
        factors[f]->keys());
    return false;
  }
  if (touches_fixed) {
    // A fixed variable has no column: its Jacobian block is dropped, its
    // value stays in the residual.
    const int nk = static_cast<int>(fpos.size());
    int kept = 0;
    for (int k = 0; k < nk; ++k) {
      if (fpos[k] < 0) continue;
      if (kept != k) scratch.jacobians[kept] = std::move(scratch.jacobians[k]);
      fpos[kept] = fpos[k];
      fdims[kept] = fdims[k];
      ++kept;
    }
    scratch.jacobians.resize(kept);
  }
  return true;
}

bool LinearizedGraph::linearizeFactor(std::size_t f, double sign, bool as_rows,
                                      UpdateResult* result) {
  const bool touches_fixed = gatherFactor(f, true);
  const Factor* evaluated = factors[f].get();
  if (factors[f]->hasModes()) {
    // The mode R holds the factor with: the one at the linearisation point
    // when it goes in, the recorded one when it comes out (the point has not
    // moved since, so they are the same unless a raised switch put the
    // nominal component in at the same point: then it is the nominal that
    // comes out).
    const int m =
        sign > 0 && !modes.at_lin_known ? factors[f]->mode(params.data()) : modes.lin_mode[f];
    if (sign > 0) {
      modes.lin_mode[f] = m;
      modes.held_nominal[f] = 0;
    }
    if (modes.dormant(*factors[f], m)) {
      scratch.cost = 0;
      return true;
    }
    if (sign < 0 && modes.held_nominal[f]) evaluated = factors[f]->modeComponent(0);
  }
  const double w = sign > 0 ? weight[f] : lin_weight[f];
  if (sign > 0) lin_weight[f] = w;
  if (w == 0) {
    scratch.cost = 0;
    return true;
  }
  if (!linearizeGathered(f, *evaluated, touches_fixed, result)) return false;
  if (w != 1) scale(w, &scratch);
  if (scratch.jacobians.empty()) return true;
  if (as_rows)
    rows.add(scratch, fpos.data(), fdims.data());
  else
    neq.add(scratch, fpos.data(), fdims.data(), sign);
  return true;
}

bool LinearizedGraph::reweighFactors(UpdateResult* result) {
  // Each reweighted factor out at the weight R holds and in at its new one,
  // at the same linearisation point: the difference of H and A^T b.
  for (int f : reweighted) {
    if (weight[f] == lin_weight[f]) continue;
    if (!linearizeFactor(f, -1.0, false, result) || !linearizeFactor(f, 1.0, false, result))
      return false;
  }
  reweighted.clear();
  return true;
}

bool LinearizedGraph::linearizeFactors(std::size_t begin, std::size_t end, bool as_rows,
                                       UpdateResult* result) {
  double cost = 0, largest = 0;
  for (std::size_t f = begin; f < end; ++f) {
    if (!linearizeFactor(f, 1.0, as_rows, result)) return false;
    cost += scratch.cost;
    largest = std::max(largest, scratch.cost);
  }
  if (!std::isfinite(cost)) {
    // Each factor is finite, their sum is not: the system cannot be trusted.
    const std::vector<FactorPtr> range(factors.begin() + begin, factors.begin() + end);
    result->status = finiteCostStatus(cost, range, estimate, "aprilsam");
    return false;
  }
  if (largest > kMaxResolvableChi2) {
    // A residual whose rounding alone exceeds one standard deviation: no
    // step computed from it resolves the estimate (finite_result.h).
    const std::vector<FactorPtr> range(factors.begin() + begin, factors.begin() + end);
    result->status = resolvableCostStatus(range, estimate, "aprilsam");
    if (!result->status.ok()) return false;
  }
  return true;
}

bool LinearizedGraph::estimateIsFinite(UpdateResult* result) {
  changed_keys.clear();
  bool finite = true;
  for (int p : solve.changed()) {
    const int v = var_at[p];
    changed_keys.push_back(keys[v]);
    for (int t = 0; t < dims[v]; ++t) finite &= std::isfinite(est[v][t]);
  }
  // The estimate is read through est (no hash lookup per key, which cost a
  // batch as much as its solve); the Status that names the variable is
  // built only on a failure, or for an empty change set, where it checks all.
  if (finite && !changed_keys.empty()) {
    result->status = Status();
    return true;
  }
  result->status = finiteEstimateStatus(estimate, "aprilsam", changed_keys);
  return result->status.ok();
}

void LinearizedGraph::applyChangedDx() {
  for (int p : solve.changed()) {
    const int v = var_at[p];
    const double* dx = solve.dx(p);
    const int d = dims[v];
    double sq = 0, inf = 0;
    for (int t = 0; t < d; ++t) {
      sq += dx[t] * dx[t];
      inf = std::max(inf, std::fabs(dx[t]));
      est[v][t] = lin[v].data[t] + dx[t];
    }
    // Values::retract's convention: plain addition, Pose2 angle wrapped.
    if (lin[v].type == VariableType::kPose2) est[v][2] = wrapAngle(est[v][2]);
    dx_sq += sq - dx_sq_of[v];
    dx_sq_of[v] = sq;
    const char m = !(inf < delta_t);  // NaN counts as moved
    moved_count += m - moved[v];
    moved[v] = m;
  }
}

}  // namespace hamal::aprilsam
