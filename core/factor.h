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
// in the Registry. To be initialised by the thesis protocol, a factor can
// predict one of its variables from the others (odometry composes, a
// landmark observation projects). To be used by initialisers that work on
// the pose graph alone (LAGO), a factor can expose the relative-pose
// measurement it holds. Tests compare factors with equals() (a read-back
// factor with the one written) instead of casting to each kind.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "core/key.h"
#include "core/pose2.h"
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

  // A guess for variable `unknown` (one of keys()) from the other keys' values
  // in `known`; false when this factor cannot tell (the default).
  virtual bool predict(Key unknown, const Values& known, Values::Entry* guess) const;

  // log |Omega| of the information the whitened residual carries (U^T U).
  // A max-mixture (factors/max_mixture_factor.h) weighs components that are
  // different factors by |Omega_j|^(1/2), so it needs this number from each;
  // nothing else does. The default is NaN, "cannot tell": a factor kind that
  // is to be a component next to another factor overrides it.
  virtual double logDetInformation() const;

  // Discrete modes: a factor whose residual depends on a choice made where it
  // is evaluated (a max-mixture's active component) says so with hasModes()
  // and names the choice at `parameters` (one pointer per key) with mode().
  // A back-end that keeps linearisations from old points (AprilSAM's R)
  // compares the mode at a factor's linearisation point with the mode at its
  // current estimate and relinearises the factor's variables when they
  // differ, as GTSAM's ISAM2UpdateParams::extraReelimKeys lets a caller ask;
  // back-ends that relinearise every iteration (ceres, cholesky) need
  // nothing. The default: no modes, mode() is 0.
  virtual bool hasModes() const;
  virtual int mode(const double* const* parameters) const;
  // The information a mode carries relative to the factor's nominal one (a
  // max-mixture's null hypothesis: its scale, e.g. 1e-12). Its gradient and
  // Hessian are that scale times the nominal's, so a back-end may keep a
  // factor whose mode is far below 1 out of its system while that mode is
  // active (the dormant_scale of AprilSAM and cholesky). The default, and
  // for an unknown mode (-1): 1. Whether a back-end keeps it out is one
  // rule for all of them: core/dormant_policy.h.
  virtual double modeInformationScale(int mode) const;
  // The factor a mode is made of: mode `mode`'s residual is this factor's
  // whitened residual times sqrt(modeInformationScale(mode)), with zero or
  // constant entries besides (a max-mixture's component). A back-end that
  // holds a factor in one mode can then add or take out another mode's
  // share without knowing the factor's class. nullptr (the default) when the
  // mode is not one factor's term.
  virtual const Factor* modeComponent(int mode) const;
  // A nominal + null hypothesis pair: exactly two modes, 0 the nominal
  // (modeComponent(0) at its full information) and 1 the null hypothesis
  // (the same factor at modeInformationScale(1)). A back-end that holds the
  // null mode can raise it to the nominal by adding (1 - scale) of the
  // component's rows at the same linearisation point. False by default.
  virtual bool isNullHypothesisPair() const;

  // A Gaussian measurement of pose `to` seen from pose `from` (from^-1 to),
  // with its information in (x, y, theta) of from's frame: what a pose-graph
  // initialiser such as LAGO reads. A factor returns one only when its
  // residual is, to first order, that measurement's error whitened by that
  // information, so that an initialiser treating it as an edge solves the
  // factor's own least-squares term; the robust loss is not part of it (an
  // initialiser decides what to do with a factor that has one). Empty (the
  // default) for every other factor: LAGO then reports it as one it could
  // not use.
  struct RelativePose {
    Key from, to;
    Pose2 measurement;
    Eigen::Matrix3d information;
  };
  virtual std::optional<RelativePose> relativePose() const;
  // A factor of this kind for another relative-pose measurement `r`: keys
  // r.from and r.to, the thesis residual (the (x, y, theta) error of
  // from^-1 to against r.measurement in from's frame) whitened by
  // r.information, and no robust loss. It lets a caller ask a back-end's
  // covariance about a relative pose (FactorWeights::residualCovariance)
  // without naming a factor class. Null (the default) for a factor that gives
  // no relativePose().
  virtual std::shared_ptr<Factor> relativePoseFactor(const RelativePose& r) const;

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
