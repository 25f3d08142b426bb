// BackendKit: what every back-end keeps besides its solver (core/backend.h):
// the input contract, the estimate, the factors, the variable layout and the
// checks on what it reports. A back-end owns one and writes only its
// numerics (plugins/example/dense_gauss_newton.cc is a whole back-end on it).
//
//  - admit(step): the step checked by checkStep (core/step.h) before anything
//    is recorded, so a bad step throws hamal::Error and leaves the back-end as
//    it was; then its guesses go into the estimate, its factors into the list
//    and its variables into the layout (core/variable_layout.h: index, fixed
//    variables, columns).
//  - finiteStatus(): a non-finite estimate or cost is never ok
//    (core/finite_result.h): the numerical-failure Status naming the culprit.
//  - Phase timing is a PhaseClock (core/phase_clock.h) per update.
//
// A back-end that keeps more than one copy of the values (cholesky: the
// estimate and a candidate) uses VariableLayout and PhaseClock on their own;
// one whose hot loops read flat arrays of its own (aprilsam's LinearizedGraph)
// uses checkStep, the finite_result.h checks and PhaseClock on their own.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/phase_clock.h"
#include "core/step.h"
#include "core/values.h"
#include "core/variable_layout.h"

namespace hamal {

class BackendKit {
 public:
  // `backend` names the back-end in every message.
  explicit BackendKit(std::string backend) : name_(std::move(backend)) {}

  // Checks `step` (checkStep; then `refuse`, when given, for what this
  // back-end cannot hold: it throws hamal::Error) and records it. Returns
  // true when a known variable became fixed (VariableLayout::add).
  bool admit(const Step& step, const std::function<void(const Step&)>& refuse = {});

  const std::string& name() const { return name_; }
  const Values& estimate() const { return estimate_; }
  Values& estimate() { return estimate_; }
  const std::vector<FactorPtr>& factors() const { return factors_; }
  const VariableLayout& layout() const { return layout_; }

  // The estimate moved by dx over the free variables, in layout() order.
  void retract(const double* dx) { layout_.retract(&estimate_, dx); }
  // Sum of every factor's chi2 at the estimate (without robust losses).
  double cost() const;
  // ok, or the numerical failure naming the first non-finite variable of the
  // estimate or else the factor that makes the cost non-finite.
  Status finiteStatus() const;
  // ok, or the numerical failure naming a variable of a part of the graph
  // that no prior or fixed variable anchors (core/gauge_freedom.h).
  Status gaugeStatus() const;

 private:
  std::string name_;
  Values estimate_;
  std::vector<FactorPtr> factors_;
  VariableLayout layout_;
};

}  // namespace hamal
