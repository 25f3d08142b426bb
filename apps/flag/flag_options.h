// FlagOptions: every threshold and noise of FLAG's localization pipeline
// (thesis sec. 4.3.3, 4.4), with the thesis' value as the default where it
// gives one and ours, said so, where it does not.
#pragma once
#include <string>

namespace hamal::flag {

struct FlagOptions {
  // Labelled landmark positions: prior sigma (thesis sec. 4.4.2: 10 cm), or
  // held fixed at the labels (the ablation of fig. 4.11).
  double landmark_sigma = 0.10;
  bool fixed_landmarks = false;
  // Nearest-neighbour association gate (thesis sec. 4.4.3.1: 50 cm). With
  // `pose_gate`, the gate grows with the predicted pose's covariance
  // (DeadReckoningUncertainty): a landmark is within `gate_sigmas`
  // Mahalanobis distances in (that covariance projected to the detection) +
  // (gate / gate_sigmas)^2 I, so `gate` is the floor, and the thesis' gate
  // wherever the pose is certain (ours: on, 3 sigmas).
  double gate = 0.50;
  bool pose_gate = true;
  double gate_sigmas = 3.0;
  // Leave out a detection with more than one landmark within its gate
  // (NearestNeighbourAssociation; ours: off, the thesis' nearest neighbour).
  bool reject_ambiguous = false;
  // The recording's odometry sigmas times this, in the odometry factors and
  // in the gate's covariance alike (1: as stated; for a recording whose
  // stated sigmas understate its drift, the scale OdometryCalibration
  // measures against a reference).
  double odometry_scale = 1.0;
  // Associate each detection with the landmark it truly came from (the
  // ground truth of a simulation, a dataset's ids) instead of by nearest
  // neighbour: the known-association reference FLAG is graded against.
  bool known_association = false;
  // Start each new pose at the Kalman update of the odometry's prediction by
  // the measurements accepted at its step (DeadReckoningUncertainty's
  // filter), not at the prediction alone (ours: on). Without it a max-mixture
  // is first evaluated at a drifted pose, where right measurements look like
  // outliers and stay switched off.
  bool corrected_guess = true;
  // Pairwise consistency check (sec. 4.3.3.1): two projections are
  // consistent within `consistency_threshold` (thesis: 10 cm); a measurement
  // is accepted with at least `min_links` consistent partners among its
  // landmark's measurements of the last `window` poses (ours: 2 and 20, i.e.
  // 10 m of travel). With `max_clique`, the accepted set is the window's
  // maximum clique (Mangelson et al. 2018) when it has min_links + 1 members.
  bool pairwise_check = true;
  double consistency_threshold = 0.10;
  int min_links = 2;
  int window = 20;
  bool max_clique = false;
  // Two-component max-mixture (sec. 4.3.3.2): the null hypothesis has
  // weight `null_weight` and information scaled by `null_scale` (ours: 0.1
  // and 1e-3, so a measurement is switched off past about 4.3 sigma).
  bool max_mixture = true;
  double null_weight = 0.1;
  double null_scale = 1e-3;
  // Where the robot starts (the thesis' runs start at a known spot, the
  // green star of fig. 4.1): prior sigma in x, y (m) and theta (rad).
  double start_sigma_xy = 0.10;
  double start_sigma_theta = 0.0175;
  // The incremental back-end, by registry spec (thesis: AprilSAM).
  std::string backend = "aprilsam";

  // Throws hamal::Error for a negative noise, gate or threshold, a window
  // or min_links below 1, or weights outside (0, 1).
  void validate() const;
};

}  // namespace hamal::flag
