// OdometryChain: the composed odometry between any two poses and its
// first-order covariance in O(1), from prefix sums. Pairwise Consistency
// Maximization (Mangelson, Dominic, Eustice, Vasudevan, ICRA 2018) closes a
// cycle through two loop closures and the odometry between their ends for
// every pair of closures; composing the chain step by step would cost the
// chain's length per pair.
//
// Conventions. A link is a RelativePose: z = x_m-1^-1 x_m with noise
// n ~ N(0, Sigma) added to (x, y, theta) in x_m-1's frame (the thesis'
// between residual). Poses are composed in the chain's own frame, from the
// first pose of the chain: P_m = P_m-1 z_m. Ad_X = [[R, -J t], [0, 1]] is
// SE(2)'s adjoint for a left perturbation Exp(xi) X, xi = (rho, phi), with
// J = [[0, -1], [1, 0]]; to first order Exp(xi) X = (t + rho + phi J t,
// theta + phi), so an additive perturbation d of (t, theta) is the left one
// A(t) xi with A(t) = [[I, J t], [0, 1]], A(t)^-1 = A(-t) = Ad_(I,t).
//
// Derivation. The noise of link m, additive in x_m-1's frame, is the left
// perturbation omega_m = A(-t_z) n_m of z_m; moved to the chain's frame it
// is u_m = Ad_P_m-1 omega_m = A(-t_P_m) G_m-1 n_m (G = diag(R_P_m-1, 1)),
// and it moves every later pose rigidly: P_n' = Exp(S_n) P_n with
// S_n = sum_{m <= n} u_m. The u_m are independent, so with
// Q_m = Cov(u_m) and the prefix sum Qbar_n = sum_{m <= n} Q_m,
//   Cov(S_b - S_a) = Qbar_max(a,b) - Qbar_min(a,b)
//   Cov(S_b - S_a, S_d - S_c) = sign(b-a) sign(d-c) (Qbar_hi - Qbar_lo) over
//                               the overlap (lo, hi] of (a, b] and (c, d].
// The chain from pose a to pose b is C = P_a^-1 P_b; to first order
// C' = P_a^-1 Exp(S_b - S_a) P_b (what happened before a moves both ends
// alike), whose additive perturbation in a's frame is
//   dC = A(t_C) Ad_P_a^-1 (S_b - S_a),
// so Cov(C) = A(t_C) Ad_P_a^-1 Cov(S_b - S_a) Ad_P_a^-T A(t_C)^T. Each
// pose, prefix sum and query is O(1); appending a link at the end is O(1).
// tests/robust/odometry_chain_test.cc checks it against step-by-step
// propagation, Sigma' = F Sigma F^T + G Sigma_m G^T, on random chains.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

#include "core/factor.h"
#include "core/pose2.h"
#include "core/relative_pose_measurement.h"

namespace hamal::robust {

// A relative pose with the covariance of its additive (x, y, theta) noise in
// its from-pose's frame.
struct UncertainPose {
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

// z^-1 with the covariance of its additive noise in z's to-frame (first order).
UncertainPose inverse(const UncertainPose& z);

// SE(2) helpers of the derivation above.
Eigen::Matrix3d adjoint(const Pose2& x);                     // Ad_X
Eigen::Matrix3d additiveFromLeft(const Eigen::Vector2d& t);  // A(t)

class OdometryChain {
 public:
  // Whether `factor` is odometry: two pose keys one id apart, with a
  // relativePose(). A link from x_m to x_m-1 is inverted; two links between
  // the same poses are fused by their information.
  static bool isOdometry(const Factor& factor);
  // Adds the factor's link; throws hamal::Error unless isOdometry(factor).
  void add(const Factor& factor);
  void add(const RelativePose& link);

  // x_a^-1 x_b composed from the odometry, with its covariance. Throws
  // hamal::Error naming the poses when a link between them is missing.
  UncertainPose between(std::uint64_t a, std::uint64_t b) const;

  // The pieces of the derivation, for cycles through several chains: P_id
  // in the chain's frame, Cov(S_b - S_a) and Cov(S_b - S_a, S_d - S_c). Each
  // throws like between() unless the poses are joined by odometry.
  const Pose2& pose(std::uint64_t id) const;
  Eigen::Matrix3d noiseCovariance(std::uint64_t a, std::uint64_t b) const;
  Eigen::Matrix3d noiseCrossCovariance(std::uint64_t a, std::uint64_t b, std::uint64_t c,
                                       std::uint64_t d) const;
  // Throws hamal::Error naming a and b unless odometry joins them.
  void requireJoined(std::uint64_t a, std::uint64_t b) const;
  // Whether odometry joins a and b: both in one segment (a run of links with
  // none missing). A pose beyond the first and last link is joined to
  // nothing (the chain holds no pose for it).
  bool joined(std::uint64_t a, std::uint64_t b) const;

  std::size_t links() const { return links_.size(); }

 private:
  void rebuild() const;
  void append(std::uint64_t id) const;
  std::size_t index(std::uint64_t id) const;  // throws when id is not in the chain

  std::map<std::uint64_t, UncertainPose> links_;  // keyed by m - 1: x_m-1^-1 x_m
  // Prefix arrays over ids first_ .. first_ + size - 1; a new segment starts
  // after every missing link.
  mutable bool dirty_ = false;
  mutable std::uint64_t first_ = 0;
  mutable std::vector<Pose2> pose_;
  mutable std::vector<Eigen::Matrix3d> qbar_;
  mutable std::vector<int> segment_;
};

}  // namespace hamal::robust
