// FLAG's localization pipeline as a StepSource (flag_localizer.h; thesis
// sec. 4.3.3).
#include "apps/flag/flag_localizer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "apps/flag/dead_reckoning_uncertainty.h"
#include "apps/flag/odometry_calibration.h"
#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/max_mixture_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace hamal::flag {

bool wallsMatch(const std::vector<double>& detected, double heading,
                const std::vector<double>& landmark, double tolerance) {
  if (detected.empty() || landmark.empty()) return true;
  for (double w : detected) {
    bool found = false;
    for (double m : landmark)
      if (std::abs(wrapAngle(w + heading - m)) <= tolerance) found = true;
    if (!found) return false;
  }
  return true;
}

FlagLocalizer::FlagLocalizer(std::vector<LandmarkLabel> labels, const Recording& recording,
                             const Pose2& start, const FlagOptions& options)
    : labels_(std::move(labels)),
      recording_(recording),
      start_(start),
      options_(options),
      association_(options.association.gate, options.association.gate_sigmas,
                   options.association.reject_ambiguous),
      consistency_(options.consistency.threshold, options.consistency.min_links,
                   options.consistency.max_clique, options.consistency.sigmas) {
  options_.validate();
  if (recording_.steps.empty()) throw Error("FLAG: the recording has no poses");
  if (labels_.empty()) throw Error("FLAG: no labelled landmarks");
  for (std::size_t k = 0; k < labels_.size(); ++k) index_[labels_[k].id] = k;
}

FactorPtr FlagLocalizer::makeFactor(std::size_t landmark, const Measurement& m) const {
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  info(0, 0) = 1.0 / (m.range_sigma * m.range_sigma);
  info(1, 1) = 1.0 / (m.bearing_sigma * m.bearing_sigma);
  FactorPtr nominal = std::make_shared<RangeBearingFactor>(X(m.pose), L(labels_[landmark].id),
                                                           m.range, m.bearing, info);
  if (!options_.max_mixture.enabled) return nominal;
  return MaxMixtureFactor::withNullHypothesis(nominal, options_.max_mixture.null_weight,
                                              options_.max_mixture.null_scale);
}

Pose2 FlagLocalizer::poseEstimate(std::size_t pose, const Values& estimate, std::size_t current,
                                  const Pose2& current_guess) const {
  if (pose == current) return current_guess;
  return estimate.pose(X(pose));
}

// The first pose: the start's prior, the landmarks' values and labels.
Pose2 FlagLocalizer::addStart(Step& step) {
  const double sxy = options_.start.sigma_xy, sth = options_.start.sigma_theta;
  const Eigen::Matrix3d info =
      Eigen::Vector3d(1 / (sxy * sxy), 1 / (sxy * sxy), 1 / (sth * sth)).asDiagonal();
  step.new_factors.push_back(std::make_shared<PriorFactor>(X(0), start_, info));
  pose_covariance_ = info.diagonal().cwiseInverse().asDiagonal();
  if (jitter()) {
    step.new_values.insert(odometryKey(0), start_);
    step.new_factors.push_back(
        std::make_shared<BetweenFactor>(X(0), odometryKey(0), Pose2(), jitterInformation()));
  }
  const double ls = options_.landmarks.sigma;
  const Eigen::Matrix2d linfo = Eigen::Matrix2d::Identity() / (ls * ls);
  for (const LandmarkLabel& l : labels_) {
    step.new_values.insert(L(l.id), l.label);
    if (options_.landmarks.fixed)
      step.fixed.push_back(L(l.id));
    else
      step.new_factors.push_back(std::make_shared<LandmarkPriorFactor>(L(l.id), l.label, linfo));
  }
  return start_;
}

// A later pose: the odometry's factor from the previous one, and the
// dead-reckoning covariance carried on.
Pose2 FlagLocalizer::addOdometry(std::size_t i, const Values& estimate, Step& step) {
  const RecordedStep& rec = recording_.steps.at(i);
  const Pose2 previous = estimate.pose(X(i - 1));
  const Eigen::Vector3d s = options_.odometry.scale * stepOdometrySigma(recording_, i);
  pose_covariance_ = propagateOdometry(pose_covariance_, previous, rec.odometry, s);
  const Eigen::Matrix3d info = s.cwiseProduct(s).cwiseInverse().asDiagonal();
  Pose2 guess;
  if (jitter()) {
    // The odometry's chain goes on from its own previous pose; the new
    // pose is expected where the chain puts it (the jitter has mean 0).
    guess = estimate.pose(odometryKey(i - 1)).compose(rec.odometry);
    step.new_values.insert(odometryKey(i), guess);
    step.new_factors.push_back(
        std::make_shared<BetweenFactor>(odometryKey(i - 1), odometryKey(i), rec.odometry, info));
    step.new_factors.push_back(
        std::make_shared<BetweenFactor>(X(i), odometryKey(i), Pose2(), jitterInformation()));
  } else {
    guess = previous.compose(rec.odometry);
    step.new_factors.push_back(std::make_shared<BetweenFactor>(X(i - 1), X(i), rec.odometry, info));
  }
  return guess;
}

// Where each landmark is believed to be now.
std::vector<Point2> FlagLocalizer::believedLandmarks(const Values& estimate) const {
  std::vector<Point2> landmarks(labels_.size());
  for (std::size_t k = 0; k < labels_.size(); ++k) {
    const Key key = L(labels_[k].id);
    landmarks[k] = estimate.contains(key) ? estimate.point(key) : labels_[k].label;
  }
  return landmarks;
}

// The landmark a detection is of: its source (known association), or the
// gated nearest neighbour of where it projects from the pose's guess.
std::optional<std::size_t> FlagLocalizer::associateDetection(const Detection& d, const Pose2& guess,
                                                             const std::vector<Point2>& landmarks) {
  std::optional<std::size_t> k;
  if (options_.association.known) {
    if (d.source.kind == Source::kCorner) {
      const auto found = index_.find(d.source.id);
      if (found != index_.end()) k = found->second;
    }
    return k;
  }
  Eigen::Matrix2d cov =
      options_.association.pose_gate
          ? projectedCovariance(pose_covariance_ + jitterCovariance(), guess, d.range, d.bearing)
          : Eigen::Matrix2d::Zero();
  // The gate stops growing at max_gate_sigma: past it a detection of
  // a corner the map lacks finds some landmark within the gate.
  const double largest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues().maxCoeff();
  const double cap = options_.association.max_gate_sigma * options_.association.max_gate_sigma;
  if (options_.association.max_gate_sigma > 0 && largest > cap) cov *= cap / largest;
  const Point2 point = project(guess, d.range, d.bearing);
  bool ambiguous = false;
  if (options_.association.wall_sigma > 0 && !d.walls.empty()) {
    // Only the landmarks whose walls match the detection's are candidates.
    const Eigen::Matrix3d heading = pose_covariance_ + jitterCovariance();
    const double sw = options_.association.wall_sigma;
    const double tolerance = options_.association.gate_sigmas * std::sqrt(heading(2, 2) + sw * sw);
    std::vector<Point2> candidates;
    std::vector<std::size_t> index;
    for (std::size_t j = 0; j < landmarks.size(); ++j) {
      if (!wallsMatch(d.walls, guess.theta, labels_[j].walls, tolerance)) {
        // Grading only: its own landmark refused, though within the gate.
        if (d.source.kind == Source::kCorner && d.source.id == labels_[j].id &&
            association_.associate(point, {landmarks[j]}, cov))
          ++stats_.gate_lost.walls;
        continue;
      }
      candidates.push_back(landmarks[j]);
      index.push_back(j);
    }
    k = association_.associate(point, candidates, cov, &ambiguous);
    if (k) k = index[*k];
  } else {
    k = association_.associate(point, landmarks, cov, &ambiguous);
  }
  if (ambiguous) ++stats_.ambiguous;
  return k;
}

// An associated detection as a measurement of pose i.
FlagLocalizer::Measurement FlagLocalizer::measurementOf(std::size_t i, const Detection& d,
                                                        const Pose2& guess) const {
  Measurement m{i, d.range, d.bearing, d.range_sigma, d.bearing_sigma, d.source, false, 0};
  if (options_.consistency.sigmas > 0) {
    // The detection's own noise, along and across its beam.
    const double a = guess.theta + d.bearing;
    Eigen::Matrix2d R;
    R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    const Eigen::Vector2d v(d.range_sigma * d.range_sigma, std::pow(d.range * d.bearing_sigma, 2));
    m.covariance = projectedCovariance(pose_covariance_, guess, d.range, d.bearing) +
                   R * v.asDiagonal() * R.transpose();
  }
  return m;
}

// An accepted measurement informs the gate's pose covariance; one of an
// earlier pose (accepted late by the pairwise check) is counted as if made
// now, which is what it says of the current pose to first order.
// With corrected_guess the same update moves the current pose's guess.
void FlagLocalizer::acceptMeasurement(std::size_t i, std::size_t landmark, const Measurement& m,
                                      const Values& estimate, Pose2& guess) {
  const Point2 at = options_.landmarks.fixed || !estimate.contains(L(labels_[landmark].id))
                        ? labels_[landmark].label
                        : estimate.point(L(labels_[landmark].id));
  double range = m.range, bearing = m.bearing;
  if (m.pose != i) {
    const Point2 local = guess.transformTo(project(estimate.pose(X(m.pose)), m.range, m.bearing));
    range = local.norm();
    bearing = std::atan2(local.y(), local.x());
  }
  const PoseBelief b =
      updateWithRangeBearing(PoseBelief{guess, pose_covariance_}, at,
                             options_.landmarks.fixed ? 0.0 : options_.landmarks.sigma, range,
                             bearing, m.range_sigma, m.bearing_sigma);
  pose_covariance_ = b.covariance;
  last_accepted_ = i;
  if (options_.odometry.corrected_guess) guess = b.mean;
}

// Drops what left the window; a measurement leaving it never accepted is a
// rejection.
void FlagLocalizer::dropMeasurementsOutOfWindow(std::size_t i) {
  const std::size_t oldest =
      i + 1 >= std::size_t(options_.consistency.window) ? i + 1 - options_.consistency.window : 0;
  for (auto it = windows_.begin(); it != windows_.end();) {
    auto& ms = it->second;
    std::size_t kept = 0;
    for (const Measurement& m : ms) {
      if (m.pose >= oldest)
        ms[kept++] = m;
      else if (!m.accepted) {
        ++stats_.rejected;
        if (m.source.kind == Source::kCorner && m.source.id == labels_[it->first].id) {
          ++stats_.rejected_correct;
          ++(m.most_partners < std::size_t(options_.consistency.min_links)
                 ? stats_.rejected_correct_few
                 : stats_.rejected_correct_inconsistent);
        }
      }
    }
    ms.resize(kept);
    it = ms.empty() ? windows_.erase(it) : std::next(it);
  }
}

// Re-checks the windows of the landmarks measured now; the measurements the
// pairwise check finds consistent become factors.
void FlagLocalizer::checkPairwiseConsistency(std::size_t i, std::vector<std::size_t> touched,
                                             const Values& estimate, Pose2& guess, Step& step) {
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  for (std::size_t k : touched) {
    auto found = windows_.find(k);
    if (found == windows_.end()) continue;
    auto& ms = found->second;
    std::vector<Point2> points;
    std::vector<bool> preferred;
    std::vector<Eigen::Matrix2d> covariances;
    points.reserve(ms.size());
    for (const Measurement& m : ms) {
      points.push_back(project(poseEstimate(m.pose, estimate, i, guess), m.range, m.bearing));
      preferred.push_back(m.accepted);
      if (options_.consistency.sigmas > 0) covariances.push_back(m.covariance);
    }
    const std::vector<bool> ok = consistency_.check(points, preferred, covariances);
    for (Measurement& m : ms) m.most_partners = std::max(m.most_partners, ms.size() - 1);
    for (std::size_t j = 0; j < ms.size(); ++j) {
      if (!ok[j] || ms[j].accepted) continue;
      ms[j].accepted = true;
      ++stats_.accepted;
      step.new_factors.push_back(makeFactor(k, ms[j]));
      if (ms[j].source.kind == Source::kCorner && ms[j].source.id == labels_[k].id) {
        ++stats_.accepted_correct;
        right_factors_.insert(step.new_factors.back().get());
      }
      acceptMeasurement(i, k, ms[j], estimate, guess);
    }
  }
}

void FlagLocalizer::updateLost(std::size_t i) {
  lost_ = i - last_accepted_ >= std::size_t(options_.lost.after) ||
          positionSigma() > options_.lost.sigma;
}

Step FlagLocalizer::step(std::size_t i, const Values& estimate) {
  const RecordedStep& rec = recording_.steps.at(i);
  Step step;
  step.index = i;
  Pose2 guess = i == 0 ? addStart(step) : addOdometry(i, estimate, step);
  const std::vector<Point2> landmarks = believedLandmarks(estimate);
  std::vector<std::size_t> touched;
  for (const Detection& d : rec.detections) {
    ++stats_.detections;
    if (d.source.kind == Source::kCorner) ++stats_.corner_detections;
    const std::optional<std::size_t> k = associateDetection(d, guess, landmarks);
    const bool labelled = d.source.kind == Source::kCorner && index_.count(d.source.id);
    if (!k) {
      if (labelled) ++stats_.gate_lost.outside;
      continue;
    }
    ++stats_.associated;
    const bool correct = d.source.kind == Source::kCorner && d.source.id == labels_[*k].id;
    if (correct) ++stats_.associated_correct;
    if (labelled && !correct) ++stats_.gate_lost.other_landmark;
    Measurement m = measurementOf(i, d, guess);
    if (!options_.consistency.check) {
      m.accepted = true;
      ++stats_.accepted;
      step.new_factors.push_back(makeFactor(*k, m));
      if (correct) {
        ++stats_.accepted_correct;
        right_factors_.insert(step.new_factors.back().get());
      }
      acceptMeasurement(i, *k, m, estimate, guess);
      continue;
    }
    windows_[*k].push_back(m);
    touched.push_back(*k);
  }
  if (options_.consistency.check) {
    // Drop what left the window, then re-check the landmarks measured now.
    dropMeasurementsOutOfWindow(i);
    checkPairwiseConsistency(i, std::move(touched), estimate, guess, step);
  }
  step.new_values.insert(X(i), guess);
  updateLost(i);
  return step;
}

Eigen::Matrix3d FlagLocalizer::jitterCovariance() const {
  const double xy = options_.odometry.jitter_xy, th = options_.odometry.jitter_theta;
  return Eigen::Vector3d(xy * xy, xy * xy, th * th).asDiagonal();
}

Eigen::Matrix3d FlagLocalizer::jitterInformation() const {
  const double xy = options_.odometry.jitter_xy, th = options_.odometry.jitter_theta;
  return Eigen::Vector3d(1 / (xy * xy), 1 / (xy * xy), 1 / (th * th)).asDiagonal();
}

double FlagLocalizer::positionSigma() const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(pose_covariance_.topLeftCorner<2, 2>());
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

}  // namespace hamal::flag
