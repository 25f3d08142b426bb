// Factor: one measurement in the factor graph (thesis sec. 2.2.2, eq. 2.6-2.8).
//
// A factor touches an ordered list of variables (its keys) and owns a
// ceres::CostFunction whose residual is already whitened: for a Gaussian
// measurement with information Omega it returns U e with U^T U = Omega, so
// the squared norm is the factor's chi2 term. Its parameter blocks are the
// keys' variables in the same order, with the sizes Values::dim gives.
//
// One definition serves every back-end: the Ceres back-end hands
// costFunction() to ceres::Problem as it is, and the Cholesky and AprilSAM
// back-ends call the same Evaluate() (through linearize(), see
// linearization.h) to assemble their normal equations.
//
// A factor may carry a robust ceres::LossFunction. chi2 is always computed
// without it (docs/PROTOCOL.md, "chi2"), the solvers minimise with it.
//
// To be written to and read from files, a factor names the g2o tag of its
// line and writes the fields after the tag; the reader side is a FactorInfo
// in the Registry. Tests compare factors with equals() (a read-back factor
// with the one written) instead of casting to each kind.
//
// What only some factors can do is a small interface of its own that a
// factor kind derives from besides Factor, and a caller asks for (a
// dynamic_cast, kept where it is asked per iteration):
//   core/variable_prediction.h       predict a variable from the others
//                                    (the thesis protocol's initial values)
//   core/relative_pose_measurement.h the rigid relative pose it measures
//                                    (LAGO, the robust front ends)
//   core/multi_modal.h               discrete modes (a max-mixture's active
//                                    component), read by the back-ends
//   core/mixture_component.h         log |Omega|, to be a max-mixture's
//                                    component next to another kind
#pragma once

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "core/key.h"
#include "core/values.h"

namespace hamal {

class Factor {
 public:
  Factor(std::vector<Key> keys, std::unique_ptr<ceres::CostFunction> cost,
         std::shared_ptr<ceres::LossFunction> loss = nullptr);
  virtual ~Factor();
  Factor(const Factor&) = delete;
  Factor& operator=(const Factor&) = delete;

  const std::vector<Key>& keys() const { return keys_; }
  ceres::CostFunction* costFunction() const { return cost_.get(); }
  // nullptr for a plain least-squares factor.
  ceres::LossFunction* lossFunction() const { return loss_.get(); }
  void setLoss(std::shared_ptr<ceres::LossFunction> loss) { loss_ = std::move(loss); }
  int residualDim() const { return cost_->num_residuals(); }

  // The tag of the factor's line in a g2o file ("EDGE_SE2").
  virtual std::string tag() const = 0;
  // Everything after the tag on that line: ids, measurement, information.
  virtual void writeFields(std::ostream& os) const = 0;

  // Whitened residual at `values` (no loss); false when Evaluate fails.
  bool evaluate(const Values& values, double* residual) const;
  // Squared norm of the whitened residual: this factor's term of chi2.
  double chi2(const Values& values) const;

  // Whether `other` holds the same measurement, as GTSAM's
  // Factor::equals(other, tol): the same dynamic type, tag and keys, and the
  // fields of the file form (writeFields) equal, numbers within `tolerance`
  // (|a - b| <= tolerance * max(1, |a|, |b|)), words exactly. The robust loss
  // is not compared: it is how a solver minimises, not the measurement (a
  // factor whose loss is part of its file form writes its parameters, as the
  // example plugin's Cauchy scale). A factor with state outside its file form
  // overrides this and calls it.
  virtual bool equals(const Factor& other, double tolerance = 1e-9) const;
  // The number comparison equals() uses; false when either is NaN.
  static bool nearlyEqual(double a, double b, double tolerance);

 private:
  std::vector<Key> keys_;
  std::unique_ptr<ceres::CostFunction> cost_;
  std::shared_ptr<ceres::LossFunction> loss_;
};

using FactorPtr = std::shared_ptr<Factor>;

}  // namespace hamal
