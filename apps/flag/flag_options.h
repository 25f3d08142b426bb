// FlagOptions: every threshold and noise of FLAG's localization pipeline
// (thesis sec. 4.3.3, 4.4), with the thesis' value as the default where it
// gives one and ours, said so, where it does not.
#pragma once
#include <string>

namespace hamal::flag {

// The back-end FLAG uses unless told otherwise: AprilSAM (the thesis'
// choice) with n_lc = 1. n_lc is the count of nodes a loop closure may soon
// touch, by which Alg. 3.1 line 10 multiplies the last incremental update's
// cost before comparing it with a batch's (batch when cost_inc x n_lc >=
// cost_batch); the reference implementation fixes it at 3. In localization
// against labelled landmarks every range-bearing factor closes a loop onto a
// landmark held near its label by a prior (or fixed), so a closure changes
// the current pose and one landmark, and the incremental update absorbs it
// at the cost of an ordinary step: there is no long loop whose later closure
// a batch would make cheaper. Pricing each increment at three times its cost
// only brings batches forward; with n_lc = 1 the time criterion batches when
// one incremental step costs what a batch does. The batch counts and errors
// of both specs are in apps/flag/README.md, their step times in
// docs/RECORD.md ("FLAG").
inline constexpr char kDefaultBackend[] = "aprilsam:n_lc=1";

struct FlagOptions {
  // Labelled landmark positions: prior sigma (thesis sec. 4.4.2: 10 cm), or
  // held fixed at the labels (the ablation of fig. 4.11).
  struct Landmarks {
    double sigma = 0.10;
    bool fixed = false;
  };
  Landmarks landmarks;

  // Which landmark a detection is of.
  struct Association {
    // Nearest-neighbour association gate (thesis sec. 4.4.3.1: 50 cm). With
    // `pose_gate`, the gate grows with the predicted pose's covariance
    // (DeadReckoningUncertainty): a landmark is within `gate_sigmas`
    // Mahalanobis distances in (that covariance projected to the detection) +
    // (gate / gate_sigmas)^2 I, so `gate` is the floor, and the thesis' gate
    // wherever the pose is certain (ours: on, 3 sigmas).
    double gate = 0.50;
    bool pose_gate = true;
    double gate_sigmas = 3.0;
    // The gate's covariance shrunk, if need be, so that its largest sigma is
    // at most this (m; 0: no bound).
    double max_gate_sigma = 0;
    // The corner's walls as a descriptor (ours; 0: off): a landmark whose
    // walls' directions (LandmarkLabel::walls) do not match the detection's
    // (Detection::walls) turned into the world by the guessed heading is no
    // candidate, whatever its distance. Each of the detection's walls must
    // lie within gate_sigmas x sqrt(heading variance + wall_sigma^2) of one
    // of the landmark's, the heading variance being the gate's (the pose's
    // covariance and the jitter's); wall_sigma (rad) is the detector's error
    // in a wall's direction against the map's. Landmarks or detections
    // without walls match anything.
    double wall_sigma = 0;
    // Leave out a detection with more than one landmark within its gate
    // (NearestNeighbourAssociation; ours: off, the thesis' nearest neighbour).
    bool reject_ambiguous = false;
    // Associate each detection with the landmark it truly came from (the
    // ground truth of a simulation, a dataset's ids) instead of by nearest
    // neighbour: the known-association reference FLAG is graded against.
    bool known = false;
  };
  Association association;

  // How the odometry enters the graph and the gate.
  struct Odometry {
    // The recording's odometry sigmas times this, in the odometry factors and
    // in the gate's covariance alike (1: as stated; for a recording whose
    // stated sigmas understate its drift, the scale OdometryCalibration
    // measures against a reference).
    double scale = 1.0;
    // The odometry pose's jitter (ours, for real logs; 0: none): sigmas in x,
    // y (m) and theta (rad) of an error on each odometry pose that does not
    // accumulate (a log's odometry read at the laser's time through clocks
    // that disagree by a varying delay: off while turning, right again
    // after). With it the graph holds the odometry's own chain of poses O_i
    // (odometry factors between them, drift sigmas) and ties each pose X_i
    // to O_i by the jitter, so a landmark that fixes X_i at a pose where the
    // odometry was off does not carry that offset into every later pose, as a
    // chain of X_i alone does.
    double jitter_xy = 0;
    double jitter_theta = 0;
    // Start each new pose at the Kalman update of the odometry's prediction by
    // the measurements accepted at its step (DeadReckoningUncertainty's
    // filter), not at the prediction alone (ours: on). Without it a max-mixture
    // is first evaluated at a drifted pose, where right measurements look like
    // outliers and stay switched off.
    bool corrected_guess = true;
  };
  Odometry odometry;

  // Pairwise consistency check (sec. 4.3.3.1): two projections are
  // consistent within `threshold` (thesis: 10 cm); a measurement is
  // accepted with at least `min_links` consistent partners among its
  // landmark's measurements of the last `window` poses (ours: 2 and 20, i.e.
  // 10 m of travel). With `max_clique`, the accepted set is the window's
  // maximum clique (Mangelson et al. 2018) when it has min_links + 1 members.
  struct Consistency {
    bool check = true;
    double threshold = 0.10;
    // With `sigmas` > 0 (ours; 0: the thesis' fixed threshold), two
    // projections are also consistent within that many sigmas of their
    // difference (PairwiseConsistency), each projection's covariance being
    // the gate filter's pose covariance and the detection's noise projected
    // to the point when it was associated.
    double sigmas = 0;
    int min_links = 2;
    int window = 20;
    bool max_clique = false;
  };
  Consistency consistency;

  // Two-component max-mixture (sec. 4.3.3.2): the null hypothesis has
  // weight `null_weight` and information scaled by `null_scale` (ours: 0.1
  // and 1e-3, so a measurement is switched off past about 4.3 sigma).
  struct MaxMixture {
    bool enabled = true;
    double null_weight = 0.1;
    double null_scale = 1e-3;
  };
  MaxMixture max_mixture;

  // Where the robot starts (the thesis' runs start at a known spot, the
  // green star of fig. 4.1): prior sigma in x, y (m) and theta (rad).
  struct Start {
    double sigma_xy = 0.10;
    double sigma_theta = 0.0175;
  };
  Start start;

  // When localization is lost, a signal that needs no ground truth: no
  // measurement accepted for `after` poses, or the gate's filter
  // (DeadReckoningUncertainty) giving the position a sigma (its covariance's
  // largest axis) beyond `sigma` metres. A run lost at any pose says so
  // in its status (ours: 40 poses, 1 m).
  struct Lost {
    int after = 40;
    double sigma = 1.0;
  };
  Lost lost;

  // The incremental back-end, by registry spec (kDefaultBackend above).
  std::string backend = kDefaultBackend;

  // Throws hamal::Error for a negative noise, gate or threshold, a window,
  // min_links or lost_after below 1, or weights outside (0, 1).
  void validate() const;
};

}  // namespace hamal::flag
