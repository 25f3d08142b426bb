// EstimateConsistency: whether a new loop closure agrees with the map built
// so far, the cycle test of Pairwise Consistency Maximization (Mangelson,
// Dominic, Eustice, Vasudevan, ICRA 2018, eq. 5) with the estimate's
// covariance in place of the odometry's, which the paper allows ("the
// relative pose ... and its uncertainty from each robot's SLAM estimate").
//
// Why. On a single robot the odometry-chain test (loop_closure_consistency.h)
// closes each cycle through the odometry between the closures' ends; over
// hundreds of poses its composed covariance grows so large (the heading
// noise turns into metres) that almost every pair of closures is
// consistent, and a random false closure survives. The estimate of a map
// whose loops are already closed knows x_i^-1 x_j far better than the
// odometry between them does.
//
// The test. For closure z (x_i -> x_j, i < j) and a back-end holding x_i
// and x_m, m the latest pose <= j it holds (the new poses of a step are not
// in it yet): the prediction x_i^-1 x_m from the estimate, with the
// covariance Sigma_im = J H^-1 J^T of a between residual with identity
// information (FactorWeights::residualCovariance, core/factor_weights.h:
// the thesis residual is the additive (x, y, theta) error in x_i's frame,
// odometry_chain.h's convention), composed with the odometry from x_m to x_j
// (independent of the estimate), against z:
//   P = (x_i^-1 x_m) C_mj,  e = (t_P - t_z, wrap(th_P - th_z)),
//   Sigma_e = F Sigma_im F^T + G Sigma_mj G^T + Sigma_z,
//   F = [[I, J R_im t_mj], [0, 1]],  G = diag(R_im, 1),
// consistent when e^T Sigma_e^-1 e is below the PCM threshold. The estimate
// is the back-end's at the start of the step, from the closures accepted
// so far; a closure that fails is rejected for good (it disagrees with
// closures already accepted as a whole, not with one of them).
#pragma once

#include <optional>

#include "backends/robust/loop_closure_consistency.h"
#include "backends/robust/odometry_chain.h"
#include "core/backend.h"
#include "core/factor_weights.h"

namespace hamal::robust {

// a b to first order: b's additive noise is in a's to-frame, the two independent.
UncertainPose compose(const UncertainPose& a, const UncertainPose& b);

// The Mahalanobis distance (squared) of the loop closure `factor`
// (loopClosureOf) against `backend`'s estimate; nothing when it cannot tell
// (the back-end holds neither end or gives no residual covariance, or the
// factor makes no relativePoseFactor to ask it with, or no odometry in
// `chain` joins x_m to x_j: an odometry gap after the map).
std::optional<double> estimateConsistency(const Backend& backend, FactorWeights& weights,
                                          const OdometryChain& chain, const Factor& factor);

}  // namespace hamal::robust
