// Localizer: online localization against a prior map (thesis sec. 5.3.2,
// fig. 5.4, eq. 5.2) with the map nodes a selection keeps (eq. 5.4), solved
// incrementally by a back-end chosen by name, and its error (eq. 5.3).
//
// For each new pose of a trial: predict it from the previous estimate and the
// odometry; take the selected map node nearest to the prediction (within the
// laser's range); match the live scan against that node's scan from the
// prediction; an accepted match becomes an L2GFactor (factors/l2g_factor.h)
// to that node. The step (new pose, odometry BetweenFactor, the L2G factor
// if any) goes to the back-end, whose estimate predicts the next pose. The
// first pose has a strong prior: the start is known (sec. 5.5).
//
// Reuse (for speed): a match of trial pose i against node j
// depends on the other selected nodes only through the guess. The guess is
// snapped to a grid (10 cm, 2 degrees, well inside ICP's convergence basin)
// and ICP starts from the snapped guess, so a match is a pure function of
// (trial, pose, node, grid cell), kept in a thread-safe MatchCache and shared
// by every climb and every map evaluated.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "apps/moss/scan_matcher.h"
#include "apps/moss/trials.h"
#include "core/backend.h"
#include "core/registry.h"

namespace hamal::moss {

// What MOSS minimises over the training trials. kRmse: the RMSE of the
// positions (as the thesis reports errors, sec. 5.5, and Alg. 5.1 line 5
// says). kSumOfNorms: eq. 5.3 to the letter, the sum over trials and poses of
// the position error's norm, taken as its mean over the poses (the same
// minimiser: the trials and their poses are fixed). The norm weighs one
// lost trial less than the RMSE's squares do.
enum class Objective { kRmse, kSumOfNorms };
// "rmse" or "sum_of_norms" (anything else is an Error naming the choices).
Objective parseObjective(const std::string& name);
const char* toString(Objective objective);

struct LocalizerConfig {
  std::string backend = "aprilsam";
  Objective objective = Objective::kRmse;
  double match_range = 3.0;  // m, nearest selected node farther: no match
  double grid_xy = 0.1;      // m, guess snapping
  double grid_theta = 2.0 * M_PI / 180.0;
  // Odometry noise as simulated (trials.h): per noise_distance, the
  // variance scaled by the measured step length (at least min_step).
  double sigma_xy = 0.30, sigma_theta = 0.1 * M_PI / 180.0, noise_distance = 10.0;
  double min_step = 0.05;     // m
  double prior_sigma = 1e-3;  // the known start
  // > 0: a match is refused (no L2G factor) when the pose it implies is
  // farther from the prediction than this chi-square allows under the
  // prediction's dead-reckoning covariance from the known start (an upper
  // bound: it ignores the matches before) plus the match's own and the
  // guess grid's. What keeps a match that slid along a corridor (aliasing)
  // out of the graph; 0: every accepted match is used, as the thesis does.
  double gate_chi2 = 0.0;
};

// The covariance of an odometry step z as the localizer weighs it (trials.h's
// noise model, the step's length at least min_step).
Eigen::Matrix3d odometryCovariance(const Pose2& z, const LocalizerConfig& config);
// Dead reckoning from the trial's known start: per pose, the covariance of
// the odometry chain's pose in the world frame (first-order propagation).
std::vector<Eigen::Matrix3d> deadReckoningCovariance(const Trial& trial,
                                                     const LocalizerConfig& config);
// The chi-square of `implied` against `predicted` (world-frame difference,
// heading wrapped) under `covariance`.
double gateChi2(const Pose2& implied, const Pose2& predicted, const Eigen::Matrix3d& covariance);

class MatchCache {
 public:
  struct Key {
    std::int32_t trial, pose, node, gx, gy, gth;
    bool operator==(const Key& o) const {
      return trial == o.trial && pose == o.pose && node == o.node && gx == o.gx && gy == o.gy &&
             gth == o.gth;
    }
  };
  struct Hash {
    std::size_t operator()(const Key& k) const;
  };
  // The cached match, or computes it with `compute` and keeps it.
  template <class F>
  ScanMatch get(const Key& key, F compute) {
    Shard& s = shards_[Hash()(key) % kShards];
    {
      std::lock_guard<std::mutex> lock(s.mutex);
      const auto it = s.map.find(key);
      if (it != s.map.end()) {
        ++hits_;
        return it->second;
      }
    }
    ScanMatch m = compute();
    ++misses_;
    std::lock_guard<std::mutex> lock(s.mutex);
    s.map.emplace(key, m);
    return m;
  }
  std::uint64_t hits() const { return hits_; }
  std::uint64_t misses() const { return misses_; }

 private:
  static constexpr int kShards = 64;
  struct Shard {
    std::mutex mutex;
    std::unordered_map<Key, ScanMatch, Hash> map;
  };
  std::array<Shard, kShards> shards_;
  std::atomic<std::uint64_t> hits_{0}, misses_{0};
};

struct Localization {
  std::vector<Pose2> estimate;  // one per trial pose
  // Per pose (pose 0 has none: the start is known): the predicted position
  // the node was chosen from, the selected node nearest to it (-1: none
  // within range) and its distance (match_range when none). Whether another
  // selection would localize this trial differently is read off these
  // (SwapEvaluator).
  std::vector<Point2> predicted;
  std::vector<int> node;
  std::vector<double> node_distance;
  // Per pose, the scan match tried against `node` (ok: it became an L2G
  // factor); a default ScanMatch where none was tried.
  std::vector<ScanMatch> matches;
  int l2g_factors = 0;
  int gated = 0;                   // matches refused by config.gate_chi2
  int failures = 0;                // back-end updates whose Status was not ok
  double sum_squared_error = 0.0;  // sum over poses of |t_ML - t_GT|^2
  double sum_error_norm = 0.0;     // sum over poses of |t_ML - t_GT| (eq. 5.3)
};

class Localizer {
 public:
  Localizer(const PriorMap& map, const std::vector<Trial>& trials, LocalizerConfig config,
            const Registry& registry, ScanMatcher matcher = ScanMatcher());
  std::size_t mapSize() const { return map_.poses.size(); }
  std::size_t trials() const { return trials_.size(); }

  const LocalizerConfig& config() const { return config_; }
  std::size_t poses(int s) const { return trials_.at(s).truth.size(); }
  // The distance localize() compares to choose a node: every caller uses this
  // one expression, so comparisons elsewhere agree with localize() bit for bit.
  double nodeDistance(int j, const Point2& predicted) const {
    return (map_.poses[j].t() - predicted).norm();
  }

  // Trial `s` localized with the nodes `selected` (selected[j] != 0 keeps node j).
  Localization localize(int s, const std::vector<char>& selected);
  // RMSE of the positions over every pose of every trial (eq. 5.3's error as
  // the thesis reports it, sec. 5.5). Per-trial RMSEs go to `per_trial`.
  double rmse(const std::vector<char>& selected, std::vector<double>* per_trial = nullptr);
  // The mean position error norm over every pose of every trial (eq. 5.3's
  // sum divided by the number of poses); per-trial means to `per_trial`.
  double meanError(const std::vector<char>& selected, std::vector<double>* per_trial = nullptr);
  // The objective MOSS minimises (config().objective) ...
  double error(const std::vector<char>& selected);
  // ... as a sum of per-trial costs (a trial's squared errors or error
  // norms) turned into the error by errorOf(sum of costs, poses).
  double cost(const Localization& l) const {
    return config_.objective == Objective::kRmse ? l.sum_squared_error : l.sum_error_norm;
  }
  double errorOf(double cost_sum, std::size_t poses) const;

  const MatchCache& cache() const { return cache_; }
  std::uint64_t localizations() const { return localizations_; }
  // Thread-seconds spent in localize() and, within it, in scan matching
  // (cache misses): where an evaluation's time goes.
  double localizeSeconds() const { return localize_ns_ * 1e-9; }
  double matchSeconds() const { return match_ns_ * 1e-9; }

 private:
  // The mean of `sum` per pose over every trial; per trial to `per_trial`.
  double meanOver(const std::vector<char>& selected, double Localization::*sum,
                  std::vector<double>* per_trial);

  const PriorMap& map_;
  const std::vector<Trial>& trials_;
  LocalizerConfig config_;
  const Registry& registry_;
  ScanMatcher matcher_;
  std::vector<std::unique_ptr<IndexedScan>> indexed_;
  std::vector<std::vector<Eigen::Matrix3d>> dead_reckoning_;  // per trial and pose (gate)
  MatchCache cache_;
  std::atomic<std::uint64_t> localizations_{0};
  std::atomic<std::uint64_t> localize_ns_{0}, match_ns_{0};
};

}  // namespace hamal::moss
