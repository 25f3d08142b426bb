// OdometryCalibration: how far a recording's stated odometry noise
// understates (or overstates) its actual drift, measured against a reference
// trajectory, so that FLAG's graph and gate use honest odometry sigmas.
//
// FLAG (thesis sec. 4.3.3) weighs each measurement against the odometry
// chain: the odometry factors' sigmas (sec. 4.4.2 gives them for the
// thesis' robot) decide how far a few landmark measurements can bend the
// chain after a stretch without landmarks, and the max-mixture's null
// hypothesis (sec. 4.3.3.2) switches off whatever the chain cannot bend to.
// When the stated sigmas are too small (Victoria Park's file: 1 cm and 0.11
// degree a step) the chain is stiffer than the drift it really has, right
// measurements after a coast become many-sigma outliers, and the
// max-mixtures switch them off and lose track.
//
// The scale is the consistency of the odometry with the reference over
// windows of k steps: from each reference pose the next k odometry steps
// are chained, the error against the reference pose k steps later is
// whitened by the chain's propagated covariance (the stated sigmas,
// DeadReckoningUncertainty's first-order propagation), and
//   scale_k^2 = mean over windows of e' P^-1 e / 3
// (the normalised estimation error squared per degree of freedom: 1 for
// honest sigmas). Drift that is correlated from step to step (a wheel-radius
// or gyro bias) shows as a scale that grows with k, so the scale FLAG uses
// is the largest over k = 1, 2, 4, ... up to the longest stretch of the
// recording without a detection (rounded up to a power of two): honest over
// the longest the robot coasts on odometry alone. A reference is needed:
// ground truth in simulation, the known-association solution for Victoria
// Park (the same solution the labels are made from).
#pragma once
#include <cstddef>
#include <vector>

#include "apps/flag/simulator.h"

namespace hamal::flag {

// Step i's stated odometry sigmas (x, y, theta in the step's frame): the
// recorded ones, or odom_sigma_* per sqrt(metre) of its length (floored at
// 1 mm, so a zero-length step does not get infinite information).
Eigen::Vector3d stepOdometrySigma(const Recording& recording, std::size_t i);

struct OdometryConsistency {
  std::size_t window = 0;  // k, steps
  std::size_t samples = 0;
  double scale = 0;  // sqrt(mean NEES / 3)
};

// scale_k for k = 1, 2, 4, ... <= max_window (windows start every
// max(1, k/2) steps). The recording's truth is the reference; odometry
// sigmas are the recorded ones, or odom_sigma_* per sqrt(metre) when a step
// has none. Throws hamal::Error for fewer than two steps or max_window 0.
std::vector<OdometryConsistency> odometryConsistency(const Recording& recording,
                                                     std::size_t max_window);

// The most consecutive steps without a detection, rounded up to a power of
// two (at least 1): the longest the robot coasts.
std::size_t longestCoast(const Recording& recording);

// An odometry whose errors are a jitter on each pose (an error that does
// not accumulate, FlagOptions::odometry.jitter_*) plus a drift: a jitter j_i
// makes step i's error j_i - j_{i-1}, of variance 2 J^2, and the jitter is
// taken to be the whole of a single step's error (in the step's frame
// against the reference): J_xy^2 = mean(e_x^2 + e_y^2) / 4, J_theta^2 =
// mean(e_theta^2) / 2, at least 1 mm and 1 mrad. Of an odometry that only
// drifts this makes a jitter all the same, and driftScale then finds the
// drift below its stated sigmas. (The jitter from consecutive steps'
// error covariance, -J^2, which tells a drift apart, was tried: on ACES,
// the log it was chosen on, FLAG's median ATE 0.25 m against 0.18 m.)
// Throws hamal::Error for a recording of fewer than three poses.
struct OdometryJitter {
  double xy = 0, theta = 0;
};
OdometryJitter odometryJitter(const Recording& recording);

// The scale of the recording's odometry sigmas (the drift) at which chains
// of `window` steps are consistent (mean NEES per degree of freedom 1) when
// each chain starts and ends on a pose with the jitter `jitter`: the start
// pose's jitter propagated through the chain, the end's added. In [0.01,
// 100] (0.01: the jitter explains the errors alone). Throws hamal::Error for
// fewer than window + 1 poses or window 0.
double driftScale(const Recording& recording, std::size_t window, const OdometryJitter& jitter);

// The largest scale_k, at least 1e-3 (a recording whose reference is its
// own odometry has none to measure).
double odometryNoiseScale(const std::vector<OdometryConsistency>& consistency);

}  // namespace hamal::flag
