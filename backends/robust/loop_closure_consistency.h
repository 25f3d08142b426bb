// LoopClosureConsistency: whether two loop closures agree, the pairwise
// consistency measure of Pairwise Consistency Maximization (Mangelson,
// Dominic, Eustice, Vasudevan, ICRA 2018, eq. 5-6), for a single robot
// whose odometry joins every pair of poses.
//
// Closures a (x_i -> x_j) and b (x_k -> x_l) close the cycle
//   x_i -(odometry)-> x_k -b-> x_l -(odometry)-> x_j -a^-1-> x_i,
// T = C_ik z_b C_lj z_a^-1, the identity when both closures and the
// odometry are right. Its error e = (x, y, theta) of T, in x_i's frame, has
// the first-order covariance of the cycle: with the notation of
// odometry_chain.h (left perturbations, S the odometry noise in the chain's
// frame, Sigma' = A(-t_z) Sigma A(-t_z)^T a closure's noise as a left
// perturbation of its from-frame),
//   e = M1 (S_k - S_i) + M2 (S_j - S_l) + Ad_C_ik omega_b - Ad_T omega_a,
//   M1 = Ad_P_i^-1, M2 = Ad_(C_ik z_b P_l^-1),
// so Sigma_e = M1 S11 M1^T + M2 S22 M2^T + M1 S12 M2^T + (M1 S12 M2^T)^T
//            + Ad_C_ik Sigma_b' Ad_C_ik^T + Ad_T Sigma_a' Ad_T^T,
// where S12 is non-zero when the two odometry chains share links (on a
// single robot they often do). Every term is O(1) from the chain's prefix
// sums. The pair is consistent when e^T Sigma_e^-1 e is below the threshold,
// by default the chi2 quantile of 3 dof at 0.99 (11.345).
//
// Odometry gaps and components. Where a link is missing (an odometry gap,
// or a graph of several components) the odometry is segments
// (odometry_chain.h). The cycle then runs through the segments where it
// can: x_i to x_k and x_l to x_j as above, else with b reversed (x_i to x_l
// and x_k to x_j), so two closures across the same gap still meet. Where
// neither pairing has odometry (closures on two sides of a gap, in two
// components, or one across a gap and one beside it) the pair cannot be
// evaluated: cycleThroughOdometry says so, and PCM's rule for such pairs is
// pairwise_consistency_maximization.h's.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>

#include "backends/robust/odometry_chain.h"
#include "core/factor.h"

namespace hamal::robust {

// A loop closure as the consistency test needs it: x_from^-1 x_to with the
// covariance of its additive noise in x_from's frame, and that noise as a
// left perturbation (precomputed: it is used for every pair).
struct LoopClosure {
  std::uint64_t from = 0, to = 0;
  UncertainPose measurement;
  Eigen::Matrix3d left_covariance = Eigen::Matrix3d::Zero();
};

// The loop closure a factor holds. Throws hamal::Error naming the factor
// (its tag and keys) when it gives no relativePose(), joins keys that are
// not poses, or has information that is not positive definite.
LoopClosure loopClosureOf(const Factor& factor);

struct CycleError {
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // (x, y, theta) of T in x_i's frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double mahalanobis2 = 0;  // e^T Sigma_e^-1 e; +inf when Sigma_e is singular
};

// The cycle of a and b through `chain`; throws hamal::Error naming the poses
// when odometry does not join a's and b's ends.
CycleError cycleError(const OdometryChain& chain, const LoopClosure& a, const LoopClosure& b);

// b the other way round: x_to -> x_from, measurement and covariances inverted.
LoopClosure reversed(const LoopClosure& b);

// The cycle of a and b through the odometry segments that join their ends
// (a's from to b's from and b's to to a's to, else b reversed); nothing when
// neither pairing is joined by odometry: the pair cannot be evaluated.
std::optional<CycleError> cycleThroughOdometry(const OdometryChain& chain, const LoopClosure& a,
                                               const LoopClosure& b);

}  // namespace hamal::robust
