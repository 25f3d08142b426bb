// GtsamFactorAdapter: hamal's factors as GTSAM's own factors, so that GTSAM's
// iSAM2 and Levenberg-Marquardt (isam2_backend.h, gtsam_lm_backend.h) solve
// the very objective hamal's chi2 evaluator scores (thesis sec. 2.2.3:
// between, prior and range-bearing factors; sec. 3.5: one protocol, one
// evaluator for every back-end).
//
// Each hamal factor becomes GTSAM's native factor with a full Gaussian noise
// model whose information is chosen so that GTSAM's squared whitened error
// equals hamal's chi2 of that factor exactly:
//
//   BetweenFactor -> gtsam::BetweenFactor<Pose2>. GTSAM's error is the
//     measurement-frame one, e_m = Local(z, a^-1 b) = D e_t with
//     D = diag(R(z_th)^T, 1) and e_t the thesis' error (factors/
//     between_factor.h). A measurement-frame factor keeps its Omega; a
//     thesis one gets D Omega D^T, for which e_m^T (D Omega D^T) e_m =
//     e_t^T Omega e_t. So hamal_bench's --residual chooses the objective of
//     every back-end alike, GTSAM's included.
//   PriorFactor -> ThesisPosePrior (gtsam_factor_adapter.cc), hamal's own
//     e = [t - t0, wrap(th - th0)] as a GTSAM NoiseModelFactorN: GTSAM's
//     PriorFactor<Pose2> error -Local(x, p0) has its translation in the frame
//     of the current heading, which no constant information maps to hamal's.
//   RangeBearingFactor -> gtsam::BearingRangeFactor<Pose2, Point2>, whose
//     error is (bearing, range), hamal's (range, bearing) swapped: P Omega P.
//   LandmarkPriorFactor -> gtsam::PriorFactor<Point2> (the same error).
//
// Any other factor (pose-point, position, max-mixture, L2G, a plugin's), and
// any factor with a robust loss, is refused with an error naming its tag and
// variables: a silent skip would make GTSAM solve another problem.
//
// A fixed variable (core/step.h) becomes a PriorFactor at its value with
// sigma kFixedSigma in every component (information 1e12): GTSAM's
// NonlinearEquality is a hard constraint whose linearisation iSAM2's
// Cholesky elimination does not take, so a strong prior holds it instead.
// The back-ends report the fixed value itself in their estimate.
//
// GTSAM's default build (GTSAM_SLOW_BUT_CORRECT_BETWEENFACTOR off) leaves the
// derivative of Local() out of BetweenFactor's Jacobian, exact only where a
// residual is zero: Gauss-Newton then stops a little above the optimum of
// this very objective (1e-4 of chi2 on a noisy test graph; tests/gtsam).
//
// Keys: a hamal Key is a kind character and a 56-bit index, GTSAM's Symbol
// exactly, so the raw value is used as it is (x5 prints as x5 in both).
#pragma once

#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/Values.h>

#include <string>
#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/step.h"
#include "core/values.h"

namespace hamal::gtsam_plugin {

// The strong prior that holds a fixed variable (see above).
constexpr double kFixedSigma = 1e-6;

inline gtsam::Key toGtsam(Key key) { return key.raw(); }
inline Key fromGtsam(gtsam::Key key) {
  return Key(static_cast<char>(key >> Key::kIndexBits), key & Key::kMaxIndex);
}

// GTSAM's factor for `factor`; throws hamal::Error naming `backend`, the
// factor's tag and keys when it has no counterpart (see above).
gtsam::NonlinearFactor::shared_ptr toGtsamFactor(const Factor& factor, const std::string& backend);

// All of `factors`, converted before anything is returned, so that an
// unknown factor throws and nothing is half added.
gtsam::NonlinearFactorGraph toGtsamFactors(const std::vector<FactorPtr>& factors,
                                           const std::string& backend);

// One variable's value as a GTSAM value (Pose2 or Point2), added to `out`.
void insertGtsamValue(Key key, const Values::Entry& entry, gtsam::Values* out);

// The strong prior that holds variable `key` at `entry` (see above).
gtsam::NonlinearFactor::shared_ptr fixedPrior(Key key, const Values::Entry& entry);

// The strong priors for the variables `step` fixes that `already` does not
// hold yet, each at its value in the step or in `estimate`, appended to
// `factors`; returns those variables (record them once the step is taken).
std::vector<Key> addFixedPriors(const Step& step, const Values& estimate,
                                const std::unordered_set<Key>& already,
                                gtsam::NonlinearFactorGraph* factors);

// Copies GTSAM's value of every variable of `estimate` that `from` holds
// into `estimate`, except the keys of `keep` (fixed variables keep their
// value). A value of a type other than the entry's throws hamal::Error.
void copyFromGtsam(const gtsam::Values& from, const std::vector<Key>& keep, Values* estimate);

// Called in a catch block around a GTSAM solve: the exception in flight as
// a numerical-failure Status naming `backend` (an indeterminant system also
// names the variable GTSAM found it near). An exception that is not a
// std::exception is rethrown.
Status gtsamFailure(const std::string& backend);

}  // namespace hamal::gtsam_plugin
