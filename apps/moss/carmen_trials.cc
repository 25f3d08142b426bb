// MOSS on a real laser log: see carmen_trials.h (thesis ch. 5).
#include "apps/moss/carmen_trials.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>

#include "apps/moss/localizer.h"
#include "core/error.h"

namespace hamal::moss {

LogOdometry parseLogOdometry(const std::string& name) {
  if (name == "log") return LogOdometry::kLog;
  if (name == "synthetic") return LogOdometry::kSynthetic;
  throw Error("--odometry: '" + name + "' is not log or synthetic");
}

const char* toString(LogOdometry odometry) {
  return odometry == LogOdometry::kLog ? "log" : "synthetic";
}

OdometryTrack::OdometryTrack(const carmen::CarmenLog& log, double slack)
    : file_(log.file), slack_(slack) {
  for (const carmen::OdometryRecord& r : log.odometry) records_.emplace_back(r.timestamp, r.pose);
  if (records_.empty()) throw Error(log.file + ": no ODOM records (use --odometry synthetic)");
  // The reader allows clocks to step back a little: order by time.
  std::stable_sort(records_.begin(), records_.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
}

Pose2 OdometryTrack::at(double time) const {
  if (time < records_.front().first - slack_ || time > records_.back().first + slack_)
    throw Error(file_ + ": no ODOM record within " + std::to_string(slack_) +
                " s of t = " + std::to_string(time) + " s");
  const auto after = std::lower_bound(records_.begin(), records_.end(), time,
                                      [](const auto& r, double t) { return r.first < t; });
  if (after == records_.begin()) return after->second;
  if (after == records_.end()) return records_.back().second;
  const auto& [t0, a] = *(after - 1);
  const auto& [t1, b] = *after;
  const double u = t1 > t0 ? (time - t0) / (t1 - t0) : 1.0;
  return carmen::interpolateOdometry(a, b, u);
}

void estimateOdometryNoise(const std::vector<Pose2>& reference, const std::vector<Pose2>& odometry,
                           double noise_distance, double min_step, double* sigma_xy,
                           double* sigma_theta) {
  if (reference.size() != odometry.size() || reference.empty())
    throw Error("estimateOdometryNoise: needs as many odometry as reference steps, at least 1");
  double sxy = 0, sth = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double scale = std::max(min_step, odometry[i].t().norm()) / noise_distance;
    sxy += (odometry[i].t() - reference[i].t()).squaredNorm() / 2 / scale;
    const double dth = wrapAngle(odometry[i].theta - reference[i].theta);
    sth += dth * dth / scale;
  }
  *sigma_xy = std::sqrt(sxy / reference.size());
  *sigma_theta = std::sqrt(sth / reference.size());
}

void CarmenTrialsOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string("--") + name + " must be > 0");
  };
  positive(scans.step, "pose_step");
  positive(scans.turn, "pose_turn_deg");
  positive(max_range, "max_range");
  positive(node_spacing, "node_spacing");
  positive(revisit_radius, "revisit_radius");
  positive(revisit_gap, "revisit_gap");
  positive(noise_distance, "noise_distance");
  if (!(train_fraction > 0 && train_fraction < 1))
    throw Error("--train_fraction must lie in (0, 1)");
  if (trial_poses < 2) throw Error("--poses must be at least 2 on a log");
  for (double v : {sigma_xy, sigma_theta})
    if (!(v >= 0) || !std::isfinite(v)) throw Error("odometry sigmas must be >= 0");
}

std::string describe(const CarmenTrialsOptions& o) {
  std::ostringstream os;
  os << "tag " << o.scans.tag << "\npose_step " << o.scans.step << "\npose_turn " << o.scans.turn
     << "\nmax_range " << o.max_range << "\nrevisit_gap " << o.revisit_gap << "\nnode_spacing "
     << o.node_spacing << "\nrevisit_radius " << o.revisit_radius << "\nposes " << o.trial_poses
     << "\ntrain_fraction " << o.train_fraction << "\nsigma_xy " << o.sigma_xy << "\nsigma_theta "
     << o.sigma_theta << "\nnoise_distance " << o.noise_distance << "\nseed " << o.seed << "\n";
  // Written only when not the first default, so folders of synthetic runs still resume.
  if (o.odometry != LogOdometry::kSynthetic) os << "odometry " << toString(o.odometry) << "\n";
  return os.str();
}

namespace {

Scan clippedPoints(const carmen::LaserScan& s, double max_range) {
  Scan out;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    if (!s.hit(i) || s.ranges[i] > max_range) continue;
    const double b = s.bearing(i);
    out.push_back(
        s.laser_offset.transformFrom(Point2(s.ranges[i] * std::cos(b), s.ranges[i] * std::sin(b))));
  }
  return out;
}

}  // namespace

CarmenTrials carmenTrials(const carmen::CarmenLog& log, const CarmenTrialsOptions& options) {
  options.validate();
  const std::vector<const carmen::LaserScan*> kept = carmen::keyScans(log, options.scans);
  CarmenTrials out;
  out.cut.kept_poses = kept.size();
  std::vector<double> along(kept.size(), 0.0);
  for (std::size_t i = 1; i < kept.size(); ++i)
    along[i] = along[i - 1] + (kept[i]->pose.t() - kept[i - 1]->pose.t()).norm();
  out.cut.path_length = along.back();
  const auto distance = [&](std::size_t i, std::size_t j) {
    return (kept[i]->pose.t() - kept[j]->pose.t()).norm();
  };

  // Revisits: within revisit_radius of a pose driven revisit_gap or more
  // before. The other poses are first visits, the map's ground.
  std::vector<char> revisit(kept.size(), 0);
  std::vector<std::size_t> revisits;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    for (std::size_t j = 0; j < i && along[i] - along[j] >= options.revisit_gap; ++j)
      if (distance(i, j) <= options.revisit_radius) {
        revisit[i] = 1;
        break;
      }
    if (revisit[i]) revisits.push_back(i);
  }
  out.cut.revisiting_poses = revisits.size();

  // The map: a first visit every node_spacing metres, unless it lies within
  // 2 revisit_radius of a revisit less than revisit_gap of path away (the
  // same pass, whose scan a trial would match against itself).
  std::vector<std::size_t> nodes;
  double last_node = -1e300;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (revisit[i]) continue;
    out.map.path.push_back(kept[i]->pose);
    ++out.cut.first_visit_poses;
    if (along[i] - last_node < options.node_spacing) continue;
    last_node = along[i];
    const bool same_pass = std::any_of(revisits.begin(), revisits.end(), [&](std::size_t r) {
      return std::abs(along[r] - along[i]) < options.revisit_gap &&
             distance(r, i) <= 2 * options.revisit_radius;
    });
    if (same_pass) {
      ++out.cut.dropped_nodes;
      continue;
    }
    nodes.push_back(i);
    out.node_times.push_back(kept[i]->timestamp);
    out.map.poses.push_back(kept[i]->pose);
    out.map.scans.push_back(clippedPoints(*kept[i], options.max_range));
    for (const Point2& p : out.map.scans.back())
      out.map_points.push_back(kept[i]->pose.transformFrom(p));
  }
  if (out.map.poses.size() < 2)
    throw Error(log.file + ": fewer than 2 map nodes (first visits away from the revisits)");

  // Trial poses: revisits within revisit_radius of a map node; their runs
  // cut into trials of N poses, each starting at the previous one's last.
  const auto trialPose = [&](std::size_t i) {
    if (!revisit[i]) return false;
    for (std::size_t j : nodes)
      if (distance(i, j) <= options.revisit_radius) return true;
    return false;
  };
  const std::size_t n = static_cast<std::size_t>(options.trial_poses);
  std::vector<std::vector<const carmen::LaserScan*>> pieces;
  std::vector<const carmen::LaserScan*> run;
  const auto flush = [&] {
    for (std::size_t a = 0; a + n <= run.size(); a += n - 1)
      pieces.emplace_back(run.begin() + a, run.begin() + a + n);
    run.clear();
  };
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (trialPose(i)) {
      ++out.cut.trial_poses;
      run.push_back(kept[i]);
    } else {
      flush();
    }
  }
  flush();
  const std::size_t train =
      static_cast<std::size_t>(std::floor(options.train_fraction * pieces.size()));
  if (train < 1 || train >= pieces.size())
    throw Error(log.file + ": " + std::to_string(pieces.size()) + " stretches of " +
                std::to_string(n) + " poses revisit the map (within --revisit_radius " +
                std::to_string(options.revisit_radius) +
                " m); a training and a test trial need at least 2");

  TrialConfig noise;
  noise.sigma_xy = out.noise.sigma_xy = options.sigma_xy;
  noise.sigma_theta = out.noise.sigma_theta = options.sigma_theta;
  noise.noise_distance = options.noise_distance;
  std::mt19937_64 rng(options.seed);
  std::unique_ptr<OdometryTrack> track;
  const auto logSteps = [&](const std::vector<const carmen::LaserScan*>& scans) {
    std::vector<Pose2> steps;
    Pose2 previous = track->at(scans.front()->timestamp);
    for (std::size_t i = 1; i < scans.size(); ++i) {
      const Pose2 next = track->at(scans[i]->timestamp);
      steps.push_back(previous.between(next));
      previous = next;
    }
    return steps;
  };
  if (options.odometry == LogOdometry::kLog) {
    // The noise is estimated on the first visits' steps alone, not on the
    // revisits the trials are cut from.
    track = std::make_unique<OdometryTrack>(log);
    std::vector<Pose2> reference, odometry;
    for (std::size_t i = 1; i < kept.size(); ++i) {
      if (revisit[i - 1] || revisit[i]) continue;
      reference.push_back(kept[i - 1]->pose.between(kept[i]->pose));
      odometry.push_back(logSteps({kept[i - 1], kept[i]}).front());
    }
    if (reference.empty()) throw Error(log.file + ": no step between two first visits");
    estimateOdometryNoise(reference, odometry, options.noise_distance, LocalizerConfig().min_step,
                          &out.noise.sigma_xy, &out.noise.sigma_theta);
    out.noise.odometry_steps = reference.size();
  }
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    Trial t;
    for (const carmen::LaserScan* s : pieces[k]) {
      t.truth.push_back(s->pose);
      t.scans.push_back(clippedPoints(*s, options.max_range));
    }
    for (std::size_t i = 1; i < t.truth.size(); ++i)
      t.length += (t.truth[i].t() - t.truth[i - 1].t()).norm();
    t.odometry = track ? logSteps(pieces[k]) : sampleOdometry(t.truth, noise, rng);
    (k < train ? out.train : out.test).push_back(std::move(t));
    (k < train ? out.times.train_spans : out.times.test_spans)
        .emplace_back(pieces[k].front()->timestamp, pieces[k].back()->timestamp);
  }
  out.times.train_until = pieces[train - 1].back()->timestamp;
  out.times.test_from = pieces[train].front()->timestamp;
  return out;
}

}  // namespace hamal::moss
