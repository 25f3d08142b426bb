// MarginalCovariances: a capability a Backend may offer besides update(): the
// covariance of chosen variables, Sigma = (H^-1)_KK for the information
// matrix H = J^T J of the whitened, robustified Jacobians (thesis eq.
// 3.6-3.7, core/linearization.h), what GTSAM's Marginals and
// ISAM2::marginalCovariance give: uncertainty ellipses, data-association
// gates, consistency checks (NEES).
//
// A back-end that offers it derives from both Backend and
// MarginalCovariances; a caller finds it with dynamic_cast, as it finds
// FactorWeights (core/factor_weights.h).
//
// Convention, the same for every back-end:
//  - Each variable's block is in its tangent space as hamal's back-ends
//    retract (Values::retract): Pose2 (x, y, theta) added to the parameters,
//    x and y in the world frame, theta in rad; Point2 (x, y). This is not
//    GTSAM's Pose2 convention, whose tangent is (x, y, theta) in the body
//    frame: Sigma_gtsam = T^T Sigma T with T = diag(R(theta), 1), R(theta)
//    the pose's rotation (to first order).
//  - Blocks are in the order of `keys`, each as wide as the variable's
//    tangent (dimension(type): 3 for a Pose2, 2 for a Point2).
//  - A fixed variable (Step::fixed) is known exactly: its rows and columns
//    are zero.
//  - The point of linearisation is the back-end's own: the estimate for a
//    batch back-end (cholesky, ceres), the linearisation points of R for
//    AprilSAM, which may lag the estimate, as iSAM2's does. Each back-end's
//    README says which.
//
// Bad input (a key the back-end does not hold, or one asked twice) throws
// hamal::Error. A covariance that cannot be computed (the last update
// failed, so the system is not the one of an accepted estimate; a system
// that is not positive definite) is a Status, with `covariance` untouched;
// an ok Status always comes with finite numbers.
#pragma once

#include <Eigen/Core>
#include <string>
#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/error.h"
#include "core/key.h"
#include "core/values.h"

namespace hamal {

class MarginalCovariances {
 public:
  virtual ~MarginalCovariances() = default;
  // The joint covariance of `keys`, a symmetric sum(dim) x sum(dim) matrix
  // (see above). Not const: a back-end may factorise to answer.
  virtual Status jointMarginalCovariance(const std::vector<Key>& keys,
                                         Eigen::MatrixXd* covariance) = 0;
  // One variable's block: jointMarginalCovariance({key}).
  Status marginalCovariance(Key key, Eigen::MatrixXd* covariance) {
    return jointMarginalCovariance({key}, covariance);
  }
};

// The bad-input rule above, for a back-end whose estimate is `values`:
// throws hamal::Error naming `backend` and the key, and returns the scalar
// size of the joint covariance.
inline long checkMarginalKeys(const std::vector<Key>& keys, const Values& values,
                              const std::string& backend) {
  std::unordered_set<Key> seen;
  long size = 0;
  for (Key key : keys) {
    if (!values.contains(key))
      throw Error(backend + ": marginal covariance of " + key.str() +
                  ", a variable the back-end does not hold");
    if (!seen.insert(key).second)
      throw Error(backend + ": marginal covariance of " + key.str() + " asked twice");
    size += values.dim(key);
  }
  return size;
}

}  // namespace hamal
