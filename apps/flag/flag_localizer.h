// FlagLocalizer: FLAG's localization pipeline as a StepSource (thesis
// sec. 4.3.3, fig. 4.4). Step i holds pose x_i with its odometry factor,
// and the range-bearing factors of the measurements accepted at step i:
//
//   1. each detection is projected through the predicted pose and given to
//      the nearest landmark estimate within the gate (association; the gate
//      grows with the pose's covariance, DeadReckoningUncertainty) whose
//      walls' directions match the detection's (with wall_sigma), or,
//      with known_association, to the landmark it truly came from (the
//      reference a dataset's ids give);
//   2. with the pairwise check, it waits among its landmark's measurements
//      of the last `window` poses until it has enough consistent partners
//      (PairwiseConsistency), re-projected through the back-end's latest
//      estimates at every step; a measurement that leaves the window
//      unaccepted is dropped;
//   3. an accepted measurement becomes a RangeBearingFactor, wrapped in a
//      two-component MaxMixtureFactor (nominal + null hypothesis) when the
//      max-mixture is on.
//
// With an odometry jitter (FlagOptions::odometry.jitter_*, ours for real
// logs) step i also holds the odometry's own pose O_i: the odometry factor
// joins O_{i-1} and O_i, and a factor of the jitter's sigmas ties X_i to
// O_i. The gate's bound (max_gate_sigma) caps the covariance it grows with.
//
// Step 0 also holds every landmark at its label, with a prior of
// landmark_sigma (fig. 4.4) or fixed (Step::fixed, the fig. 4.11 ablation),
// and the start pose's prior.
#pragma once
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "apps/flag/flag_options.h"
#include "apps/flag/nearest_neighbour_association.h"
#include "apps/flag/pairwise_consistency.h"
#include "apps/flag/simulator.h"
#include "core/step_source.h"

namespace hamal::flag {

struct LandmarkLabel {
  std::uint64_t id = 0;  // landmark L(id)
  Point2 label;
  // The directions its walls leave it in (world, rad; map_corners.h); empty:
  // not known, and any detection's walls match.
  std::vector<double> walls;
};

// Association graded against the simulator's ground truth. A measurement is
// correct when it came from the corner it was associated with.
struct AssociationStats {
  std::size_t detections = 0;  // all detections
  std::size_t associated = 0;  // within the gate of a landmark
  std::size_t ambiguous = 0;   // left out: more than one landmark within the gate
  std::size_t associated_correct = 0;
  std::size_t accepted = 0;  // became factors
  std::size_t accepted_correct = 0;
  std::size_t rejected = 0;          // associated but dropped by the pairwise check
  std::size_t rejected_correct = 0;  // ... of them, associated with the right corner
  // ... of those, why: never had min_links other measurements of the
  // landmark in its window (too few sightings), or had them but too few
  // within the consistency threshold (inconsistent).
  std::size_t rejected_correct_few = 0, rejected_correct_inconsistent = 0;
  std::size_t corner_detections = 0;  // detections that came from a corner
  // Of the detections of a labelled corner, those the gate lost: no
  // landmark within it, or another landmark nearest within it (a corner the
  // known association keeps; the pose's error outgrew the gate); and those
  // whose own landmark was within the gate but refused by the walls'
  // directions (FlagOptions::association.wall_sigma).
  struct GateLosses {
    std::size_t outside = 0;         // no landmark within the gate
    std::size_t other_landmark = 0;  // another landmark associated
    std::size_t walls = 0;           // its own refused by the walls
  } gate_lost;
  // Of the factors, the fraction from the right corner.
  double precision() const { return accepted ? double(accepted_correct) / accepted : 1.0; }
  // Of the detections of corners, the fraction that became right factors.
  double recall() const {
    return corner_detections ? double(accepted_correct) / corner_detections : 1.0;
  }
};

// Whether a detection's walls (robot frame) turned by `heading` match a
// landmark's (world): each within `tolerance` (rad) of one of the
// landmark's. Either without walls matches.
bool wallsMatch(const std::vector<double>& detected, double heading,
                const std::vector<double>& landmark, double tolerance);

class FlagLocalizer : public StepSource {
 public:
  // Throws hamal::Error for bad options or an empty recording.
  FlagLocalizer(std::vector<LandmarkLabel> labels, const Recording& recording, const Pose2& start,
                const FlagOptions& options);
  std::size_t size() const override { return recording_.steps.size(); }
  Step step(std::size_t i, const Values& estimate) override;
  const AssociationStats& stats() const { return stats_; }
  // Whether a factor this localizer made came from the right corner (for
  // grading which stage lost a right association: FlagRun::Factors).
  bool rightFactor(const Factor* f) const { return right_factors_.count(f) > 0; }
  // Whether localization is lost after the latest step (FlagOptions::
  // lost.after, lost.sigma), and the position sigma that decides it.
  bool lost() const { return lost_; }
  double positionSigma() const;

 private:
  struct Measurement {
    std::size_t pose;
    double range, bearing, range_sigma, bearing_sigma;
    Source source;
    bool accepted;
    std::size_t most_partners = 0;  // the most other measurements in its window at a check
    // Its point's covariance when associated (pose and detection noise).
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  };
  FactorPtr makeFactor(std::size_t landmark, const Measurement& m) const;
  // The odometry chain's pose O_i (FlagOptions::odometry.jitter_*).
  bool jitter() const { return options_.odometry.jitter_xy > 0; }
  static Key odometryKey(std::size_t i) { return Key('o', i); }
  Eigen::Matrix3d jitterInformation() const;
  Eigen::Matrix3d jitterCovariance() const;  // zero without a jitter
  Pose2 poseEstimate(std::size_t pose, const Values& estimate, std::size_t current,
                     const Pose2& current_guess) const;
  // The steps of step(): the start's or the odometry's factors (returning
  // the pose's guess), association, the pairwise check over the window.
  Pose2 addStart(Step& step);
  Pose2 addOdometry(std::size_t i, const Values& estimate, Step& step);
  std::vector<Point2> believedLandmarks(const Values& estimate) const;
  std::optional<std::size_t> associateDetection(const Detection& d, const Pose2& guess,
                                                const std::vector<Point2>& landmarks);
  Measurement measurementOf(std::size_t i, const Detection& d, const Pose2& guess) const;
  void acceptMeasurement(std::size_t i, std::size_t landmark, const Measurement& m,
                         const Values& estimate, Pose2& guess);
  void dropMeasurementsOutOfWindow(std::size_t i);
  void checkPairwiseConsistency(std::size_t i, std::vector<std::size_t> touched,
                                const Values& estimate, Pose2& guess, Step& step);
  void updateLost(std::size_t i);

  std::vector<LandmarkLabel> labels_;
  const Recording& recording_;
  Pose2 start_;
  FlagOptions options_;
  NearestNeighbourAssociation association_;
  PairwiseConsistency consistency_;
  std::unordered_map<std::size_t, std::vector<Measurement>> windows_;  // per landmark index
  std::unordered_map<std::uint64_t, std::size_t> index_;               // landmark id -> index
  AssociationStats stats_;
  std::unordered_set<const Factor*> right_factors_;
  // The current pose's covariance (DeadReckoningUncertainty) for the gate.
  Eigen::Matrix3d pose_covariance_ = Eigen::Matrix3d::Zero();
  std::size_t last_accepted_ = 0;  // the latest step that accepted a measurement
  bool lost_ = false;
};

}  // namespace hamal::flag
