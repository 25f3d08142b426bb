// MaxMixtureFactor: see max_mixture_factor.h (Olson & Agarwal, RSS 2012).
#include "factors/max_mixture_factor.h"

#include <ceres/cost_function.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>
#include <typeinfo>

#include "core/error.h"
#include "core/line_tokens.h"
#include "core/mixture_component.h"
#include "factors/full_precision.h"

namespace hamal {

namespace {

struct Prepared {
  bool shared = false;  // every component is the same factor
  std::vector<const ceres::CostFunction*> costs;
  std::vector<double> scales, sqrt_scales;
  std::vector<double> offsets;  // 2 (c_max - c_j)
  std::vector<int> dims;
};

bool allSameFactor(const std::vector<MaxMixtureFactor::Component>& components) {
  for (const auto& c : components)
    if (c.factor != components.front().factor) return false;
  return true;
}

// Checks the components and computes what evaluation needs.
Prepared prepare(const std::vector<MaxMixtureFactor::Component>& components) {
  if (components.size() < 2)
    throw Error("MaxMixtureFactor: needs at least two components, got " +
                std::to_string(components.size()));
  for (std::size_t j = 0; j < components.size(); ++j) {
    const auto& c = components[j];
    const std::string which = "MaxMixtureFactor: component " + std::to_string(j);
    if (!c.factor) throw Error(which + " has no factor");
    if (!(c.weight > 0.0 && c.weight < 1.0))
      throw Error(which + " has weight " + std::to_string(c.weight) + ", outside (0, 1)");
    if (!(c.information_scale > 0.0 && std::isfinite(c.information_scale)))
      throw Error(which + " has information scale " + std::to_string(c.information_scale) +
                  ", which is not positive and finite");
    if (c.factor->lossFunction())
      throw Error(which + " (" + c.factor->tag() +
                  ") has a robust loss; a component must be a plain Gaussian factor");
    if (dynamic_cast<const MaxMixtureFactor*>(c.factor.get()))
      throw Error(which + " is itself a max-mixture; list its components instead");
    const auto& f0 = *components.front().factor;
    if (c.factor->keys() != f0.keys())
      throw Error(which + " (" + c.factor->tag() + ") has other keys than component 0 (" +
                  f0.tag() + ")");
    if (c.factor->costFunction()->parameter_block_sizes() !=
        f0.costFunction()->parameter_block_sizes())
      throw Error(which + " (" + c.factor->tag() +
                  ") has other parameter block sizes than component 0");
  }
  const bool same = allSameFactor(components);
  Prepared p;
  p.shared = same;
  std::vector<double> c_log;
  for (std::size_t j = 0; j < components.size(); ++j) {
    const auto& c = components[j];
    const int d = c.factor->residualDim();
    // log|s Omega| = d log s + log|Omega|; the second term is common to all
    // components when they are one factor, and then it cancels in c_max - c_j.
    double log_det = d * std::log(c.information_scale);
    if (!same) {
      const double own = logDetInformationOf(*c.factor);
      if (!std::isfinite(own))
        throw Error(
            "MaxMixtureFactor: component " + std::to_string(j) + " (" + c.factor->tag() +
            ") does not tell its information's log-determinant "
            "(MixtureComponent::logDetInformation), which weighs components that are different "
            "factors");
      log_det += own;
    }
    c_log.push_back(std::log(c.weight) + 0.5 * log_det);
    p.costs.push_back(c.factor->costFunction());
    p.scales.push_back(c.information_scale);
    p.sqrt_scales.push_back(std::sqrt(c.information_scale));
    p.dims.push_back(d);
  }
  const double c_max = *std::max_element(c_log.begin(), c_log.end());
  for (double c : c_log) p.offsets.push_back(2.0 * (c_max - c));
  return p;
}

// The max-mixture's residual: the active component's scaled residual, zero
// padding, and the constant sqrt(2 (c_max - c_j)).
class MaxMixtureCost : public ceres::CostFunction {
 public:
  explicit MaxMixtureCost(Prepared p) : p_(std::move(p)) {
    set_num_residuals(*std::max_element(p_.dims.begin(), p_.dims.end()) + 1);
    *mutable_parameter_block_sizes() = p_.costs.front()->parameter_block_sizes();
  }

  // cost_j at the parameters; +infinity where component j fails. Writes
  // component j's unscaled residual into `scratch` (num_residuals() long).
  double componentCost(std::size_t j, double const* const* parameters, double* scratch) const {
    if (!p_.costs[j]->Evaluate(parameters, scratch, nullptr))
      return std::numeric_limits<double>::infinity();
    double sq = 0.0;
    for (int i = 0; i < p_.dims[j]; ++i) sq += scratch[i] * scratch[i];
    const double cost = p_.scales[j] * sq + p_.offsets[j];
    return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
  }

  // When every component is one cost function (the nominal + null pair),
  // its residual is evaluated once: the components differ in scale only.
  // The active component for the squared residual `sq`, or -1.
  int chooseShared(double sq) const {
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < p_.costs.size(); ++j) {
      const double cost = p_.scales[j] * sq + p_.offsets[j];
      if (cost < best_cost) {  // false for NaN
        best_cost = cost;
        best = static_cast<int>(j);
      }
    }
    return best;
  }

  double squaredNorm(const double* r, int d) const {
    double sq = 0.0;
    for (int i = 0; i < d; ++i) sq += r[i] * r[i];
    return sq;
  }

  // The active component, or -1 when none can be evaluated. `scratch` ends
  // up holding the last evaluated component's residual; `*last` says which.
  int select(double const* const* parameters, double* scratch, int* last) const {
    if (p_.shared) {
      *last = 0;
      if (!p_.costs[0]->Evaluate(parameters, scratch, nullptr)) return -1;
      return chooseShared(squaredNorm(scratch, p_.dims[0]));
    }
    int best = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < p_.costs.size(); ++j) {
      const double cost = componentCost(j, parameters, scratch);
      *last = static_cast<int>(j);
      if (cost < best_cost) {
        best_cost = cost;
        best = static_cast<int>(j);
      }
    }
    return best;
  }

  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    // Each component writes its residual into `residual` (it is long
    // enough), so selecting needs no buffer of its own.
    int last = -1, j = -1;
    if (p_.shared) {
      // One evaluation, with the Jacobians if asked, serves every component.
      if (!p_.costs[0]->Evaluate(parameters, residual, jacobians)) return false;
      j = chooseShared(squaredNorm(residual, p_.dims[0]));
      if (j < 0) return false;
    } else {
      j = select(parameters, residual, &last);
      if (j < 0) return false;
    }
    if (!p_.shared && (jacobians || j != last)) {
      // Component j's Jacobian blocks are dims[j] x size row-major: the top
      // rows of ours, which have the same layout.
      if (!p_.costs[j]->Evaluate(parameters, residual, jacobians)) return false;
    }
    const int m = num_residuals(), d = p_.dims[j];
    const double s = p_.sqrt_scales[j];
    for (int i = 0; i < d; ++i) residual[i] *= s;
    for (int i = d; i < m - 1; ++i) residual[i] = 0.0;
    residual[m - 1] = std::sqrt(p_.offsets[j]);
    if (jacobians) {
      const auto& sizes = parameter_block_sizes();
      for (std::size_t k = 0; k < sizes.size(); ++k) {
        if (!jacobians[k]) continue;
        double* jk = jacobians[k];
        const int n = sizes[k];
        for (int i = 0; i < d * n; ++i) jk[i] *= s;
        std::fill(jk + d * n, jk + m * n, 0.0);
      }
    }
    return true;
  }

  const Prepared& prepared() const { return p_; }

 private:
  Prepared p_;
};

const MaxMixtureCost& mixtureCost(const Factor& f) {
  return static_cast<const MaxMixtureCost&>(*f.costFunction());
}

std::vector<const double*> parametersOf(const Factor& f, const Values& values) {
  std::vector<const double*> params;
  for (Key k : f.keys()) params.push_back(values.data(k));
  return params;
}

}  // namespace

MaxMixtureFactor::MaxMixtureFactor(std::vector<Component> components)
    : Factor(components.empty() || !components.front().factor ? std::vector<Key>{}
                                                              : components.front().factor->keys(),
             std::make_unique<MaxMixtureCost>(prepare(components))),
      components_(std::move(components)) {}

std::shared_ptr<MaxMixtureFactor> MaxMixtureFactor::withNullHypothesis(FactorPtr nominal,
                                                                       double null_weight,
                                                                       double null_scale) {
  const std::string problem = nullHypothesisProblem(null_weight, null_scale);
  if (!problem.empty()) throw Error("MaxMixtureFactor: " + problem);
  return std::make_shared<MaxMixtureFactor>(std::vector<Component>{
      {nominal, 1.0 - null_weight, 1.0}, {nominal, null_weight, null_scale}});
}

std::string MaxMixtureFactor::nullHypothesisProblem(double null_weight, double null_scale,
                                                    const std::string& weight_name,
                                                    const std::string& scale_name) {
  const auto text = [](double v) {
    std::ostringstream os;
    os << v;
    return os.str();
  };
  if (!(null_weight > 0.0 && null_weight < 1.0))
    return weight_name + " is " + text(null_weight) +
           ": a null hypothesis' weight must be in (0, 1)";
  if (!(null_scale > 0.0 && null_scale <= 1.0))
    return scale_name + " is " + text(null_scale) +
           ": a null hypothesis' information scale must be in (0, 1] (it doubts the measurement)";
  return "";
}

const std::vector<MaxMixtureFactor::Component>& MaxMixtureFactor::components() const {
  return components_;
}

std::size_t MaxMixtureFactor::activeComponent(const Values& values) const {
  const auto params = parametersOf(*this, values);
  std::vector<double> scratch(residualDim());
  int last = -1;
  const int j = mixtureCost(*this).select(params.data(), scratch.data(), &last);
  if (j < 0) throw Error("MaxMixtureFactor: no component can be evaluated at these values");
  return static_cast<std::size_t>(j);
}

int MaxMixtureFactor::mode(const double* const* parameters) const {
  // Called for every mixture on a moved variable after each AprilSAM
  // update: no allocation for the usual residual sizes.
  std::array<double, 16> small;
  std::vector<double> large;
  double* scratch = small.data();
  if (residualDim() > static_cast<int>(small.size())) {
    large.resize(residualDim());
    scratch = large.data();
  }
  int last = -1;
  return mixtureCost(*this).select(parameters, scratch, &last);
}

double MaxMixtureFactor::modeInformationScale(int mode) const {
  if (mode < 0 || mode >= static_cast<int>(components_.size())) return 1.0;
  return components_[static_cast<std::size_t>(mode)].information_scale;
}

const Factor* MaxMixtureFactor::modeComponent(int mode) const {
  if (mode < 0 || mode >= static_cast<int>(components_.size())) return nullptr;
  return components_[static_cast<std::size_t>(mode)].factor.get();
}

double MaxMixtureFactor::componentCost(std::size_t j, const Values& values) const {
  if (j >= components_.size())
    throw Error("MaxMixtureFactor: no component " + std::to_string(j) + " of " +
                std::to_string(components_.size()));
  const auto params = parametersOf(*this, values);
  std::vector<double> scratch(residualDim());
  return mixtureCost(*this).componentCost(j, params.data(), scratch.data());
}

double MaxMixtureFactor::componentOffset(std::size_t j) const {
  return mixtureCost(*this).prepared().offsets.at(j);
}

bool MaxMixtureFactor::isNullHypothesisPair() const {
  return components_.size() == 2 && components_[0].factor == components_[1].factor &&
         components_[0].information_scale == 1.0 &&
         components_[0].weight == 1.0 - components_[1].weight;
}

std::string MaxMixtureFactor::tag() const { return "EDGE_MAXMIX"; }

void MaxMixtureFactor::writeFields(std::ostream& os) const {
  if (!isNullHypothesisPair())
    throw Error(
        "MaxMixtureFactor: only a nominal + null hypothesis pair (withNullHypothesis) has a "
        "file line; this mixture has " +
        std::to_string(components_.size()) + " components of other shape");
  const Component& null = components_[1];
  {
    FullPrecision full(os);
    os << null.weight << ' ' << null.information_scale << ' ';
  }
  os << null.factor->tag() << ' ';
  null.factor->writeFields(os);
}

bool MaxMixtureFactor::predict(Key unknown, const Values& known, Values::Entry* guess) const {
  return predictVariable(*components_.front().factor, unknown, known, guess);
}

bool MaxMixtureFactor::equals(const Factor& other, double tolerance) const {
  if (typeid(other) != typeid(*this) || other.keys() != keys()) return false;
  const auto& theirs = static_cast<const MaxMixtureFactor&>(other).components_;
  if (theirs.size() != components_.size()) return false;
  for (std::size_t j = 0; j < components_.size(); ++j) {
    const Component &a = components_[j], &b = theirs[j];
    if (!nearlyEqual(a.weight, b.weight, tolerance) ||
        !nearlyEqual(a.information_scale, b.information_scale, tolerance) ||
        !a.factor->equals(*b.factor, tolerance))
      return false;
  }
  return true;
}

FactorInfo maxMixtureFactorInfo() {
  return {"g2o", "EDGE_MAXMIX",
          "max-mixture of a measurement and its null hypothesis (Olson & Agarwal 2012): w_null "
          "scale_null <inner tag> <inner fields>; nominal weight 1 - w_null, null information = "
          "scale_null * inner information (hamal tag)",
          [](LineTokens& t) -> FactorPtr {
            const double w = t.number("w_null");
            const double s = t.number("scale_null");
            const std::string problem =
                MaxMixtureFactor::nullHypothesisProblem(w, s, "w_null", "scale_null");
            if (!problem.empty()) t.fail("EDGE_MAXMIX: " + problem);
            if (!t.registry())
              t.fail("EDGE_MAXMIX: the line is read without a registry to parse its inner line");
            FactorPtr inner = t.registry()->parseFactor(t.rest("the inner tag"));
            if (dynamic_cast<const MaxMixtureFactor*>(inner.get()))
              t.fail(
                  "EDGE_MAXMIX: the inner line is itself an EDGE_MAXMIX; a mixture's "
                  "components are plain factors");
            try {
              return MaxMixtureFactor::withNullHypothesis(std::move(inner), w, s);
            } catch (const Error& e) {
              t.fail(e.what());
            }
          }};
}

}  // namespace hamal
