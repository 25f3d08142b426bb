// ComponentSwitchHook: see component_switch_hook.h (MultiModal::mode; thesis
// ch. 4's max-mixtures in AprilSAM's R, ch. 3).
#include "backends/aprilsam/component_switch_hook.h"

#include <cmath>
#include <sstream>

namespace hamal::aprilsam {

void ComponentSwitchHook::run(PhaseClock* clock, UpdateResult* result) {
  if (!g_.modes().any || g_.record().broken) return;
  constexpr int kMaxPasses = 4;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    const bool all_raised = findSwitches();
    if (switched_.empty()) return;
    if (!(all_raised ? raise(clock, result) : relinearize(clock, result))) return;
  }
}

bool ComponentSwitchHook::findSwitches() {
  // Only variables whose estimate changed can have changed a mode.
  const ModeTracking& modes = g_.modes();
  factor_stamps_.newPass(g_.factors().size());
  switched_.clear();
  bool all_raised = true;
  for (int p : g_.solve().changed()) {
    for (int f : modes.of_var[g_.order().varAt(p)]) {
      if (!factor_stamps_.visit(f)) continue;
      const int m = g_.modeAtEstimate(f);
      if (m == modes.lin_mode[f]) continue;
      switched_.push_back(f);
      all_raised &= modes.null_pair[f] && modes.lin_mode[f] == 1 && m == 0;
    }
  }
  return all_raised;
}

bool ComponentSwitchHook::raise(PhaseClock* clock, UpdateResult* result) {
  // Every switch is a nominal + null pair turning nominal: its nominal
  // component is added at the linearisation point R holds it at, as rows
  // (addRows) like a new factor's, instead of relinearising its variables
  // and every factor on them and refactoring R from there.
  long rows = 0;
  for (int f : switched_) rows += g_.modes().of_factor[f]->modeComponent(0)->residualDim();
  const bool as_rows = options_.factor_update == AprilSamOptions::FactorUpdate::kRank &&
                       rows <= options_.rank_update_max_rows;
  g_.rows().clear();
  g_.neq().clear(g_.chol().size());
  for (int f : switched_)
    if (!raiseToNominal(f, as_rows, result)) {
      g_.record().broken = true;
      return false;
    }
  std::ostringstream why;
  why << "; " << switched_.size() << " factor(s) switched mode: nominal rows added";
  result->reason += why.str();
  return solveAfterSwitch(
      as_rows ? g_.chol().addRows(g_.rows()) : g_.chol().update(g_.neq(), false), clock, result);
}

bool ComponentSwitchHook::relinearize(PhaseClock* clock, UpdateResult* result) {
  // The switched factors' free variables move their linearisation point
  // to the estimate; every factor on them is relinearised.
  const FactorTable& factors = g_.factors();
  VariableTable& vars = g_.variables();
  factor_stamps_.newPass(factors.size());
  var_stamps_.newPass(vars.size());
  vars_.clear();
  touched_.clear();
  for (int f : switched_)
    for (int v : factors.vars(f)) {
      if (vars.fixed(v) || !var_stamps_.visit(v)) continue;
      vars_.push_back(v);
      for (int h : factors.factorsOf(v))
        if (factor_stamps_.visit(h)) touched_.push_back(h);
    }
  g_.neq().clear(g_.chol().size());
  for (int f : touched_)
    if (!g_.linearizeFactor(f, -1.0, false, result)) {
      g_.record().broken = true;
      return false;
    }
  for (int v : vars_) vars.moveLinearizationPoint(v);
  for (int f : touched_)
    if (!g_.linearizeFactor(f, 1.0, false, result)) {
      g_.record().broken = true;
      return false;
    }
  result->variables_relinearized += vars_.size();
  std::ostringstream why;
  why << "; " << switched_.size() << " factor(s) switched mode: " << vars_.size()
      << " variable(s) relinearised";
  result->reason += why.str();
  return solveAfterSwitch(g_.chol().update(g_.neq(), false), clock, result);
}

bool ComponentSwitchHook::raiseToNominal(std::size_t f, bool as_rows, UpdateResult* result) {
  // R holds held x (the nominal's J^T J, J^T r) at the linearisation point
  // (held = the null's scale, 0 when dormant); the nominal mode needs
  // 1 x: the difference is (1 - held) x, rows sqrt(1 - held) [J | r], a
  // rank update like a new factor's.
  ModeTracking& modes = g_.modes();
  const MultiModal& factor = *modes.of_factor[f];
  const int m = modes.lin_mode[f];
  const double held = modes.dormant(factor, m) ? 0.0 : factor.modeInformationScale(m);
  const double w = (1.0 - held) * g_.factors().linWeight(f);
  if (!g_.addComponent(f, *factor.modeComponent(0), w, as_rows, result)) return false;
  modes.lin_mode[f] = 0;
  modes.held_nominal[f] = 1;
  return true;
}

bool ComponentSwitchHook::solveAfterSwitch(const IncrementalCholesky::Outcome& out,
                                           PhaseClock* clock, UpdateResult* result) {
  if (!out.ok) {
    const Key bad = g_.variables().key(g_.order().varAt(out.failed_position));
    batch_.run(result->reason + "; not positive definite at " + bad.str() + ": damped batch", true,
               clock, result);
    return false;
  }
  result->columns_recomputed += out.columns_recomputed;
  g_.solve().solve(g_.chol(), options_.backsolve.kind == AprilSamOptions::Backsolve::kFull,
                   options_.backsolve.tolerance);
  g_.applyChangedDx();
  return true;
}

}  // namespace hamal::aprilsam
