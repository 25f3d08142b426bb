// MaxMixtureFactor: a measurement that is one of k hypotheses (Olson &
// Agarwal, "Inference on networks of mixtures for robust robot mapping",
// RSS 2012), the robust loop-closure model the thesis' FLAG builds on
// (ch. 4) and the one hamal's robust benchmark measures against false loop
// closures.
//
// Each component j is a factor over the same keys with weight w_j and
// information Omega_j = s_j Omega(factor j) (s_j = information_scale). The
// mixture's likelihood is approximated by its largest component,
//   p(z | x) ~ max_j w_j |Omega_j|^(1/2) exp(-chi2_j(x) / 2),
//   chi2_j(x) = s_j |r_j(x)|^2  (r_j the factor's whitened residual),
// and at every evaluation the active component is the one that attains the
// max, i.e. the one with the smallest
//   cost_j(x) = chi2_j(x) + 2 (c_max - c_j),
//   c_j = log w_j + log|Omega_j| / 2,  c_max = max_j c_j.
// The residual returned is [ sqrt(s_j) r_j ; 0-padding ; sqrt(2 (c_max - c_j)) ]
// for the active j, with the Jacobian of sqrt(s_j) r_j and zero rows below it
// (the constant entry has no derivative). Its squared norm is cost_j: the
// negative log of the max-mixture up to one constant per factor, chosen
// (as in GTSAM's and Olson & Agarwal's max-mixture code, an extra residual
// entry) so that the factor's chi2 is never negative and, for the usual
// nominal + null hypothesis pair, equals the nominal factor's chi2 while the
// nominal component is active. The residual has max_j dim(r_j) + 1 entries.
//
// Components that are the same factor object (as withNullHypothesis makes
// them) differ only in s_j, so c_j needs log|Omega| of nothing but the scale:
// c_j = log w_j + d log(s_j) / 2 + (a shared constant). Components that are
// different factors need each factor's log|Omega| (core/mixture_component.h);
// the constructor refuses a factor that is not a MixtureComponent.
//
// Components may not carry a robust loss of their own, nor be max-mixtures
// themselves (the scale would then also scale the inner mixture's constant);
// the mixture as a whole may carry one (Factor::setLoss).
//
// File form (g2o, a hamal tag; factors/README.md): the nominal + null pair,
//   EDGE_MAXMIX w_null scale_null <inner tag> <inner fields...>
// with component 0 the inner factor at weight 1 - w_null and scale 1, and
// component 1 the same factor at weight w_null and scale scale_null.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/factor.h"
#include "core/multi_modal.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class MaxMixtureFactor : public Factor, public MultiModal, public VariablePrediction {
 public:
  struct Component {
    FactorPtr factor;              // same keys as the other components
    double weight;                 // w_j in (0, 1)
    double information_scale = 1;  // Omega_j = scale * (factor's information)
  };
  // Throws hamal::Error for fewer than two components, a null factor, keys
  // or parameter block sizes that differ between components, a weight
  // outside (0, 1), a scale that is not positive and finite, a component
  // with a loss or that is a max-mixture, and different component factors
  // that are not MixtureComponents with a finite log-determinant.
  explicit MaxMixtureFactor(std::vector<Component> components);
  // The usual two components: `nominal`, and a null hypothesis with the same
  // measurement, information scaled by null_scale (e.g. 1e-6..1e-12) and
  // weight null_weight. Component 0 is the nominal one (weight 1 - null_weight).
  // Throws hamal::Error with nullHypothesisProblem's reason.
  static std::shared_ptr<MaxMixtureFactor> withNullHypothesis(FactorPtr nominal, double null_weight,
                                                              double null_scale);
  // Why (null_weight, null_scale) is no null hypothesis, "" when it is one:
  // the weight in (0, 1); the scale in (0, 1], since the null hypothesis
  // doubts the measurement (above 1 it would be more certain of it than the
  // nominal component). The one check behind every input that makes such
  // a pair (options, flags, file fields), named as that input names them.
  static std::string nullHypothesisProblem(double null_weight, double null_scale,
                                           const std::string& weight_name = "null_weight",
                                           const std::string& scale_name = "null_scale");
  const std::vector<Component>& components() const;
  // The component with the largest weighted likelihood at `values` (the
  // lowest index on a tie). Throws hamal::Error when no component can be
  // evaluated there.
  std::size_t activeComponent(const Values& values) const;
  // cost_j at `values` (see above); +infinity where component j's Evaluate
  // fails. The active component is the one with the smallest.
  double componentCost(std::size_t j, const Values& values) const;
  // 2 (c_max - c_j): the constant part of cost_j.
  double componentOffset(std::size_t j) const;

  // Its modes are its components: mode() is activeComponent() at the
  // parameters (-1 where no component can be evaluated), so a back-end that
  // keeps old linearisations notices a switch (core/multi_modal.h).
  int mode(const double* const* parameters) const override;
  // Component `mode`'s information_scale (1 for -1 or a mode it does not
  // have): the null hypothesis of a nominal + null pair is scale_null.
  double modeInformationScale(int mode) const override;
  // Component `mode`'s factor (nullptr for -1 or a mode it does not have).
  const Factor* modeComponent(int mode) const override;

  // True for the nominal + null pair withNullHypothesis makes (and the file
  // form reads): the only shape that has a file line.
  bool isNullHypothesisPair() const override;
  // "EDGE_MAXMIX".
  std::string tag() const override;
  // "w_null scale_null <inner tag> <inner fields>", 17 significant digits.
  // Throws hamal::Error unless isNullHypothesisPair().
  void writeFields(std::ostream& os) const override;
  // The nominal (component 0) factor's prediction: a guess for a new
  // variable is taken as if the measurement were right. False when that
  // factor predicts nothing.
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;
  // The same components in the same order: weights and scales within
  // `tolerance` (Factor::nearlyEqual), component factors equal. Any shape,
  // also one without a file line.
  bool equals(const Factor& other, double tolerance = 1e-9) const override;

 private:
  std::vector<Component> components_;
};

// The registry entry ("g2o", "EDGE_MAXMIX"): reads the inner line through the
// registry it is read with (Registry::parseFactor), so it wraps any factor
// kind registered for g2o, a plugin's too.
FactorInfo maxMixtureFactorInfo();

}  // namespace hamal
