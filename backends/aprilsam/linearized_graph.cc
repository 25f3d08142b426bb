// LinearizedGraph: see linearized_graph.h (thesis sec. 3.3-3.4, Alg. 3.1).
#include "backends/aprilsam/linearized_graph.h"

#include <algorithm>
#include <cmath>

#include "core/finite_result.h"

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

int LinearizedGraph::addVariable(Key key, const Values::Entry& guess, bool fixed) {
  const int v = vars_.add(key, guess, fixed);
  order_.add(v, fixed);
  if (!fixed) {
    chol_.append(vars_.dim(v));
    solve_.append();
  }
  moved_.add();
  factors_.addVariable();
  modes_.of_var.emplace_back();
  return v;
}

int LinearizedGraph::addFactor(const FactorPtr& factor) {
  const int f = factors_.add(factor, vars_);
  const IndexRange vars = factors_.vars(f);
  modes_.add(f, *factor, vars.begin(), vars.size());
  return f;
}

std::vector<int> LinearizedGraph::layOutOrder(const std::vector<int>& order) {
  order_.layOut(order);
  const int m = order_.size();
  std::vector<int> dims(m);
  for (int p = 0; p < m; ++p) dims[p] = vars_.dim(order_.varAt(p));
  return dims;
}

int LinearizedGraph::modeAtEstimate(std::size_t f) {
  const IndexRange vars = factors_.vars(f);
  params_.resize(vars.size());
  for (int k = 0; k < vars.size(); ++k) params_[k] = vars_.est(vars[k]);
  return modes_.of_factor[f]->mode(params_.data());
}

int LinearizedGraph::modeAtLinearizationPoint(std::size_t f) {
  const IndexRange vars = factors_.vars(f);
  params_.resize(vars.size());
  for (int k = 0; k < vars.size(); ++k) params_[k] = vars_.lin(vars[k]).data.data();
  return modes_.of_factor[f]->mode(params_.data());
}

bool LinearizedGraph::gatherFactor(std::size_t f, const int* positions) {
  const IndexRange vars = factors_.vars(f);
  const int n = vars.size();
  params_.resize(n);
  fpos_.resize(n);
  fdims_.resize(n);
  bool touches_fixed = false;
  for (int k = 0; k < n; ++k) {
    const int v = vars[k];
    params_[k] = vars_.lin(v).data.data();
    fpos_[k] = positions[v];
    fdims_[k] = vars_.dim(v);
    touches_fixed |= positions[v] < 0;
  }
  return touches_fixed;
}

bool LinearizedGraph::linearizeGathered(std::size_t f, const Factor& factor, bool touches_fixed,
                                        UpdateResult* result) {
  if (!linearize(factor, params_.data(), &scratch_)) {
    const Factor& held = *factors_.factor(f);
    result->status = Status::numericalFailure(
        "aprilsam: a " + held.tag() +
            " factor does not evaluate to finite numbers at the linearisation point",
        held.keys());
    return false;
  }
  if (touches_fixed) {
    // A fixed variable has no column: its Jacobian block is dropped, its
    // value stays in the residual.
    const int nk = static_cast<int>(fpos_.size());
    int kept = 0;
    for (int k = 0; k < nk; ++k) {
      if (fpos_[k] < 0) continue;
      if (kept != k) scratch_.jacobians[kept] = std::move(scratch_.jacobians[k]);
      fpos_[kept] = fpos_[k];
      fdims_[kept] = fdims_[k];
      ++kept;
    }
    scratch_.jacobians.resize(kept);
  }
  return true;
}

bool LinearizedGraph::linearizeFactorAt(std::size_t f, double sign, bool as_rows,
                                        const int* positions, UpdateResult* result) {
  const bool touches_fixed = gatherFactor(f, positions);
  const Factor& factor = *factors_.factor(f);
  const Factor* evaluated = &factor;
  if (const MultiModal* moded = modes_.of_factor[f]) {
    // The mode R holds the factor with: the one at the linearisation point
    // when it goes in, the recorded one when it comes out (the point has not
    // moved since, so they are the same unless a raised switch put the
    // nominal component in at the same point: then it is the nominal that
    // comes out).
    const int m =
        sign > 0 && !modes_.at_lin_known ? moded->mode(params_.data()) : modes_.lin_mode[f];
    if (sign > 0) {
      modes_.lin_mode[f] = m;
      modes_.held_nominal[f] = 0;
    }
    if (modes_.dormant(*moded, m)) {
      scratch_.cost = 0;
      return true;
    }
    if (sign < 0 && modes_.held_nominal[f]) evaluated = moded->modeComponent(0);
  }
  const double w = sign > 0 ? factors_.holdAtWeight(f) : factors_.linWeight(f);
  if (w == 0) {
    scratch_.cost = 0;
    return true;
  }
  if (!linearizeGathered(f, *evaluated, touches_fixed, result)) return false;
  if (w != 1) scale(w, &scratch_);
  if (scratch_.jacobians.empty()) return true;
  if (as_rows)
    rows_.add(scratch_, fpos_.data(), fdims_.data());
  else
    neq_.add(scratch_, fpos_.data(), fdims_.data(), sign);
  return true;
}

bool LinearizedGraph::addComponent(std::size_t f, const Factor& component, double w, bool as_rows,
                                   UpdateResult* result) {
  const bool touches_fixed = gatherFactor(f, order_.positions());
  if (!linearizeGathered(f, component, touches_fixed, result)) return false;
  if (scratch_.jacobians.empty()) return true;
  if (as_rows) {
    const double s = std::sqrt(w);
    scratch_.residual *= s;
    for (auto& j : scratch_.jacobians) j *= s;
    rows_.add(scratch_, fpos_.data(), fdims_.data());
  } else {
    neq_.add(scratch_, fpos_.data(), fdims_.data(), w);
  }
  return true;
}

bool LinearizedGraph::reweighFactors(UpdateResult* result) {
  // Each reweighted factor out at the weight R holds and in at its new one,
  // at the same linearisation point: the difference of H and A^T b.
  for (int f : factors_.reweighted()) {
    if (factors_.weight(f) == factors_.linWeight(f)) continue;
    if (!linearizeFactor(f, -1.0, false, result) || !linearizeFactor(f, 1.0, false, result))
      return false;
  }
  factors_.clearReweighted();
  return true;
}

bool LinearizedGraph::linearizeFactors(std::size_t begin, std::size_t end, bool as_rows,
                                       UpdateResult* result) {
  double cost = 0, largest = 0;
  for (std::size_t f = begin; f < end; ++f) {
    if (!linearizeFactor(f, 1.0, as_rows, result)) return false;
    cost += scratch_.cost;
    largest = std::max(largest, scratch_.cost);
  }
  if (!std::isfinite(cost)) {
    // Each factor is finite, their sum is not: the system cannot be trusted.
    const std::vector<FactorPtr> range(factors_.all().begin() + begin,
                                       factors_.all().begin() + end);
    result->status = finiteCostStatus(cost, range, vars_.estimate(), "aprilsam");
    return false;
  }
  if (largest > kMaxResolvableChi2) {
    // A residual whose rounding alone exceeds one standard deviation: no
    // step computed from it resolves the estimate (finite_result.h).
    const std::vector<FactorPtr> range(factors_.all().begin() + begin,
                                       factors_.all().begin() + end);
    result->status = resolvableCostStatus(range, vars_.estimate(), "aprilsam");
    if (!result->status.ok()) return false;
  }
  return true;
}

bool LinearizedGraph::estimateIsFinite(UpdateResult* result) {
  changed_keys_.clear();
  bool finite = true;
  for (int p : solve_.changed()) {
    const int v = order_.varAt(p);
    changed_keys_.push_back(vars_.key(v));
    finite &= vars_.estimateIsFinite(v);
  }
  // The estimate is read through the table's pointers (no hash lookup per
  // key, which cost a batch as much as its solve); the Status that names
  // the variable is built only on a failure, or for an empty change set,
  // where it checks all.
  if (finite && !changed_keys_.empty()) {
    result->status = Status();
    return true;
  }
  result->status = finiteEstimateStatus(vars_.estimate(), "aprilsam", changed_keys_);
  return result->status.ok();
}

void LinearizedGraph::resetChangedEstimates() {
  for (int p : solve_.changed()) vars_.resetEstimate(order_.varAt(p));
}

void LinearizedGraph::applyChangedDx() {
  for (int p : solve_.changed()) {
    const int v = order_.varAt(p);
    double sq, inf;
    vars_.retract(v, solve_.dx(p), &sq, &inf);
    moved_.record(v, sq, inf);
  }
}

}  // namespace hamal::aprilsam
