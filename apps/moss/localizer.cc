// Localizer: see localizer.h (thesis sec. 5.3.2, eq. 5.2-5.4).
#include "apps/moss/localizer.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>

#include "apps/bench/step_runner.h"
#include "core/error.h"
#include "core/stopwatch.h"
#include "factors/between_factor.h"
#include "factors/l2g_factor.h"
#include "factors/prior_factor.h"

namespace hamal::moss {

std::size_t MatchCache::Hash::operator()(const Key& k) const {
  std::uint64_t h = 1469598103934665603ull;
  for (std::int32_t v : {k.trial, k.pose, k.node, k.gx, k.gy, k.gth}) {
    h ^= static_cast<std::uint32_t>(v);
    h *= 1099511628211ull;
  }
  return static_cast<std::size_t>(h ^ (h >> 29));
}

Localizer::Localizer(const PriorMap& map, const std::vector<Trial>& trials, LocalizerConfig config,
                     const Registry& registry, ScanMatcher matcher)
    : map_(map),
      trials_(trials),
      config_(std::move(config)),
      registry_(registry),
      matcher_(matcher) {
  const double reach = std::max(matcher_.config().gate_coarse, matcher_.config().gate_fine);
  for (const Scan& s : map_.scans) indexed_.push_back(std::make_unique<IndexedScan>(s, reach));
  if (config_.gate_chi2 > 0)
    for (const Trial& t : trials_) dead_reckoning_.push_back(deadReckoningCovariance(t, config_));
  registry_.makeBackend(config_.backend);  // an unknown name fails here, not in a thread
}

Eigen::Matrix3d odometryCovariance(const Pose2& z, const LocalizerConfig& config) {
  const double d = std::max(config.min_step, z.t().norm());
  const double sxy = stepSigma(config.sigma_xy, d, config.noise_distance);
  const double sth = stepSigma(config.sigma_theta, d, config.noise_distance);
  return Eigen::Vector3d(sxy * sxy, sxy * sxy, sth * sth).asDiagonal();
}

std::vector<Eigen::Matrix3d> deadReckoningCovariance(const Trial& trial,
                                                     const LocalizerConfig& config) {
  std::vector<Eigen::Matrix3d> out(trial.truth.size(), Eigen::Matrix3d::Zero());
  if (trial.truth.empty()) return out;
  Pose2 p = trial.truth[0];
  out[0] = Eigen::Vector3d::Constant(config.prior_sigma * config.prior_sigma).asDiagonal();
  for (std::size_t i = 1; i < out.size(); ++i) {
    const Pose2& z = trial.odometry[i - 1];
    const double c = std::cos(p.theta), s = std::sin(p.theta);
    Eigen::Matrix3d jp = Eigen::Matrix3d::Identity(), jz = Eigen::Matrix3d::Identity();
    jp(0, 2) = -s * z.x - c * z.y;
    jp(1, 2) = c * z.x - s * z.y;
    jz.topLeftCorner<2, 2>() << c, -s, s, c;
    out[i] = jp * out[i - 1] * jp.transpose() + jz * odometryCovariance(z, config) * jz.transpose();
    p = p.compose(z);
  }
  return out;
}

double gateChi2(const Pose2& implied, const Pose2& predicted, const Eigen::Matrix3d& covariance) {
  const Eigen::Vector3d e(implied.x - predicted.x, implied.y - predicted.y,
                          wrapAngle(implied.theta - predicted.theta));
  return e.dot(covariance.ldlt().solve(e));
}

namespace {

// A trial as steps (eq. 5.2): step 0 holds the known start with its prior;
// step i predicts pose i from the back-end's estimate of pose i-1 (or its
// prediction when that estimate is not finite) and the odometry, and adds
// the L2G factor `match` finds for the prediction, if any.
class TrialSteps : public StepSource {
 public:
  using Match = std::function<FactorPtr(std::size_t i, const Pose2& predicted)>;
  TrialSteps(const Trial& trial, const LocalizerConfig& config, Match match)
      : trial_(trial), config_(config), match_(std::move(match)) {}
  std::size_t size() const override { return trial_.truth.size(); }
  Step step(std::size_t i, const Values& estimate) override {
    Step step;
    step.index = i;
    if (i == 0) {
      const double ps = config_.prior_sigma;
      step.new_values.insert(X(0), trial_.truth[0]);
      step.new_factors.push_back(std::make_shared<PriorFactor>(
          X(0), trial_.truth[0], Eigen::Matrix3d::Identity() / (ps * ps)));
      previous_ = trial_.truth[0];
      return step;
    }
    if (i > 1) {
      const Pose2 p = estimate.pose(X(i - 1));
      previous_ = std::isfinite(p.x + p.y + p.theta) ? p : previous_;
    }
    const Pose2& z = trial_.odometry[i - 1];
    const Pose2 predicted = previous_.compose(z);
    step.new_values.insert(X(i), predicted);
    step.new_factors.push_back(
        std::make_shared<BetweenFactor>(X(i - 1), X(i), z, odometryInformation(z)));
    if (FactorPtr l2g = match_(i, predicted)) step.new_factors.push_back(std::move(l2g));
    previous_ = predicted;  // until the back-end's estimate of pose i replaces it
    return step;
  }

 private:
  Eigen::Matrix3d odometryInformation(const Pose2& z) const {
    return Eigen::Matrix3d(odometryCovariance(z, config_).diagonal().cwiseInverse().asDiagonal());
  }

  const Trial& trial_;
  const LocalizerConfig& config_;
  Match match_;
  Pose2 previous_;
};

std::uint64_t nanoseconds(const Stopwatch& watch) {
  return static_cast<std::uint64_t>(watch.seconds() * 1e9);
}

}  // namespace

Localization Localizer::localize(int s, const std::vector<char>& selected) {
  const Stopwatch watch;
  const Trial& trial = trials_.at(s);
  const std::size_t n = trial.truth.size();
  std::unique_ptr<Backend> backend = registry_.makeBackend(config_.backend);
  Localization out;
  out.predicted.assign(n, trial.truth[0].t());
  out.node.assign(n, -1);
  out.node_distance.assign(n, config_.match_range);
  out.matches.assign(n, ScanMatch());
  // The selected node nearest to the prediction, matched from it (cached).
  const auto match = [&](std::size_t i, const Pose2& predicted) -> FactorPtr {
    int best = -1;
    double best_d = config_.match_range;
    for (std::size_t j = 0; j < selected.size(); ++j) {
      if (!selected[j]) continue;
      const double d = nodeDistance(static_cast<int>(j), predicted.t());
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(j);
      }
    }
    out.predicted[i] = predicted.t();
    out.node[i] = best;
    out.node_distance[i] = best_d;
    if (best < 0) return nullptr;
    const Pose2 guess = map_.poses[best].between(predicted);
    const MatchCache::Key key{
        s,
        static_cast<std::int32_t>(i),
        best,
        static_cast<std::int32_t>(std::lround(guess.x / config_.grid_xy)),
        static_cast<std::int32_t>(std::lround(guess.y / config_.grid_xy)),
        static_cast<std::int32_t>(std::lround(guess.theta / config_.grid_theta))};
    const ScanMatch m = cache_.get(key, [&] {
      const Pose2 snapped(key.gx * config_.grid_xy, key.gy * config_.grid_xy,
                          wrapAngle(key.gth * config_.grid_theta));
      const Stopwatch match_watch;
      ScanMatch result = matcher_.match(*indexed_[best], trial.scans[i], snapped);
      match_ns_ += nanoseconds(match_watch);
      return result;
    });
    out.matches[i] = m;
    if (!m.ok) return nullptr;
    if (config_.gate_chi2 > 0) {
      // The match's covariance in the world frame, and the guess grid's.
      const double c = std::cos(map_.poses[best].theta), sn = std::sin(map_.poses[best].theta);
      Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
      r.topLeftCorner<2, 2>() << c, -sn, sn, c;
      const Eigen::Matrix3d cov =
          dead_reckoning_.at(s).at(i) + r * m.information.inverse() * r.transpose() +
          Eigen::Vector3d(config_.grid_xy * config_.grid_xy, config_.grid_xy * config_.grid_xy,
                          config_.grid_theta * config_.grid_theta)
              .asDiagonal()
              .toDenseMatrix();
      if (gateChi2(map_.poses[best].compose(m.relative), predicted, cov) > config_.gate_chi2) {
        ++out.gated;
        out.matches[i].ok = false;  // not an L2G factor
        return nullptr;
      }
    }
    ++out.l2g_factors;
    return std::make_shared<L2GFactor>(X(i), static_cast<std::uint64_t>(best), map_.poses[best],
                                       m.relative, m.information);
  };
  TrialSteps steps(trial, config_, match);
  apps::RunOptions options;
  options.score = false;  // graded by its error against the truth (eq. 5.3)
  const apps::RunResult run = apps::runSteps(steps, *backend, config_.backend, options);
  out.failures = static_cast<int>(apps::summarizeRows(run.rows).non_ok_steps);
  const Values& est = backend->estimate();
  for (std::size_t i = 0; i < n; ++i) {
    Pose2 p = est.pose(X(i));
    if (!std::isfinite(p.x + p.y + p.theta)) {
      ++out.failures;
      p = trial.truth[0];
    }
    out.estimate.push_back(p);
    out.sum_squared_error += (p.t() - trial.truth[i].t()).squaredNorm();
    out.sum_error_norm += (p.t() - trial.truth[i].t()).norm();
  }
  ++localizations_;
  localize_ns_ += nanoseconds(watch);
  return out;
}

double Localizer::meanOver(const std::vector<char>& selected, double Localization::*sum,
                           std::vector<double>* per_trial) {
  double total = 0.0;
  std::size_t count = 0;
  if (per_trial) per_trial->clear();
  for (std::size_t s = 0; s < trials_.size(); ++s) {
    const Localization l = localize(static_cast<int>(s), selected);
    total += l.*sum;
    count += l.estimate.size();
    if (per_trial) per_trial->push_back(l.*sum / l.estimate.size());
  }
  return count ? total / count : 0.0;
}

double Localizer::rmse(const std::vector<char>& selected, std::vector<double>* per_trial) {
  const double mse = meanOver(selected, &Localization::sum_squared_error, per_trial);
  if (per_trial)
    for (double& e : *per_trial) e = std::sqrt(e);
  return std::sqrt(mse);
}

double Localizer::meanError(const std::vector<char>& selected, std::vector<double>* per_trial) {
  return meanOver(selected, &Localization::sum_error_norm, per_trial);
}

double Localizer::error(const std::vector<char>& selected) {
  return config_.objective == Objective::kRmse ? rmse(selected) : meanError(selected);
}

double Localizer::errorOf(double cost_sum, std::size_t poses) const {
  if (!poses) return 0.0;
  return config_.objective == Objective::kRmse ? std::sqrt(cost_sum / poses) : cost_sum / poses;
}

Objective parseObjective(const std::string& name) {
  if (name == "rmse") return Objective::kRmse;
  if (name == "sum_of_norms") return Objective::kSumOfNorms;
  throw Error("--objective: '" + name + "' is not rmse or sum_of_norms");
}

const char* toString(Objective objective) {
  return objective == Objective::kRmse ? "rmse" : "sum_of_norms";
}

}  // namespace hamal::moss
