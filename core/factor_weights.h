// FactorWeights: a capability a Backend may offer besides update(): scaling
// one factor's term of the objective by a weight w >= 0, so that w |r|^2
// replaces |r|^2 (w = 0 takes the factor out, w = 1 is the factor as it
// came). Graduated non-convexity (Yang et al., RA-L 2020) solves one such
// weighted least-squares problem per outer iteration and changes the
// weights of a few factors between them; a back-end that keeps old
// linearisations (AprilSAM's R) can then update only the rows those factors
// touch instead of being rebuilt (backends/robust/graduated_non_convexity.h).
//
// A back-end that offers it derives from both Backend and FactorWeights; a
// caller finds it with dynamic_cast. A new weight takes effect at the next
// update(), which may be an empty Step.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hamal {

class Factor;

class FactorWeights {
 public:
  virtual ~FactorWeights() = default;
  // `factor` is one the back-end has received in a Step (compared by
  // address). Throws hamal::Error for a factor it does not hold or a weight
  // that is not finite and >= 0, and then changes nothing.
  virtual void setFactorWeight(const Factor* factor, double weight) = 0;
  // The weight set last (1 for a factor never reweighted). Throws
  // hamal::Error for a factor the back-end does not hold.
  virtual double factorWeight(const Factor* factor) const = 0;

  // Optional: G = J H^-1 J^T for the whitened Jacobians J of `factors`
  // (stacked in that order, each without its weight) at the back-end's
  // linearisation points, H the system it holds now (with every factor at
  // the weight it holds it with; a factor it has not received, on variables
  // it holds, counts at weight 0). It predicts how reweighting those factors
  // moves their residuals without solving: raising their weights by D (a
  // diagonal of weight changes, one per residual entry) takes the stacked
  // residual r to (I + G D)^-1 r to first order (Woodbury), so graduated
  // non-convexity can anneal a few new factors on the factorisation the
  // back-end already has. False (the default) when the back-end cannot
  // tell; then `g` is untouched.
  virtual bool residualCovariance(const std::vector<const Factor*>& factors, Eigen::MatrixXd* g) {
    (void)factors;
    (void)g;
    return false;
  }

  // Optional: when a variable of `factors` is off the point the back-end's
  // factorisation holds it at by more than the back-end's own
  // relinearisation rule allows, the next update() relinearises (true). A
  // back-end that keeps old linearisations between batches (AprilSAM)
  // builds a reweighted factor's rows at its variables' old points; after a
  // loop has moved them, the weighted solve answers a problem the factor
  // does not pose, and its residual says nothing about the weight. False
  // (the default) when nothing is off or the back-end cannot tell.
  virtual bool relinearizeAtNextUpdate(const std::vector<const Factor*>& factors) {
    (void)factors;
    return false;
  }
};

}  // namespace hamal
