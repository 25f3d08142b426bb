// Trials: see trials.h (thesis sec. 5.5).
#include "apps/moss/trials.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "apps/common/builtin_name.h"
#include "core/error.h"

namespace hamal::moss {

namespace {

constexpr double kGoalReached = 0.3;  // m: a waypoint this close is reached
constexpr int kMaxCycles = 20000;     // control cycles of one run (2000 s)

std::mt19937_64 streamRng(std::uint64_t seed, int stream, int index) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(stream), static_cast<std::uint32_t>(index)};
  return std::mt19937_64(seq);
}

// Drives from `start` through `goals()` (a callback giving the next goal)
// until `done` says so; returns the dense path.
template <class NextGoal, class Done>
std::vector<Pose2> drive(const Pose2& start, const std::vector<Segment>& segments,
                         const DynamicWindow& planner, NextGoal next_goal, Done done,
                         int max_cycles) {
  RobotState s;
  s.pose = start;
  std::vector<Pose2> path{start};
  double length = 0.0;
  Point2 goal;
  if (!next_goal(s.pose, &goal)) return path;
  int since_progress = 0;
  double best_distance = (goal - s.pose.t()).norm();
  for (int cycle = 0; cycle < max_cycles; ++cycle) {
    double v, w;
    planner.control(s, goal, segments, &v, &w);
    planner.advance(&s, v, w);
    length += (s.pose.t() - path.back().t()).norm();
    path.push_back(s.pose);
    if (done(length)) break;
    const double d = (goal - s.pose.t()).norm();
    if (d < best_distance - 0.05) {
      best_distance = d;
      since_progress = 0;
    } else {
      ++since_progress;
    }
    // Reached, or stuck for 10 s: the next goal.
    if (d < kGoalReached || since_progress > 100) {
      if (!next_goal(s.pose, &goal)) break;
      best_distance = (goal - s.pose.t()).norm();
      since_progress = 0;
    }
  }
  return path;
}

}  // namespace

TrialConfig scenarioConfig(const std::string& world_name) {
  TrialConfig c;
  if (apps::lowerCase(world_name) == "square") {
    c.map_poses = 204;
    c.poses = 204;
    c.min_length = 35.0;
    c.max_length = 50.0;
    c.obstacles = 6;
    c.waypoint_sigma = 0.5;
  }
  return c;
}

std::vector<Pose2> discretise(const std::vector<Pose2>& path, int n, double* length) {
  if (n < 2) throw Error("discretise: need at least 2 poses, got " + std::to_string(n));
  std::vector<double> s(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i)
    s[i] = s[i - 1] + (path[i].t() - path[i - 1].t()).norm();
  if (length) *length = s.back();
  std::vector<Pose2> out;
  std::size_t j = 0;
  for (int k = 0; k < n; ++k) {
    const double target = s.back() * k / (n - 1);
    while (j + 1 < path.size() - 1 && s[j + 1] < target) ++j;
    const std::size_t j1 = std::min(j + 1, path.size() - 1);
    const double seg = s[j1] - s[j];
    const double u = seg > 0 ? std::clamp((target - s[j]) / seg, 0.0, 1.0) : 0.0;
    const Point2 p = (1 - u) * path[j].t() + u * path[j1].t();
    const double th = path[j].theta + u * wrapAngle(path[j1].theta - path[j].theta);
    out.emplace_back(p.x(), p.y(), wrapAngle(th));
  }
  return out;
}

PriorMap mappingRun(const World& world, const TrialConfig& config, std::uint64_t seed) {
  std::mt19937_64 rng = streamRng(seed, 7, 0);
  const DynamicWindow planner(config.planner);
  std::size_t next = 0;
  // The planner moves on from a waypoint it is stuck short of: the map
  // would then cover less than the route, so that is an error here.
  const auto reached = [&](const Pose2& at) {
    const Point2 goal = world.route[next - 1];
    const double d = (goal - at.t()).norm();
    if (d < kGoalReached) return;
    std::ostringstream os;
    os << "world " << world.name << ": the mapping run stopped " << d
       << " m short of ROUTE waypoint " << next << " of " << world.route.size() << " (" << goal.x()
       << ", " << goal.y() << "), at (" << at.x << ", " << at.y
       << "): the Dynamic Window planner finds no way there (a passage "
       << "too narrow, a corner too tight?)";
    throw Error(os.str());
  };
  const auto next_goal = [&](const Pose2& at, Point2* goal) {
    if (next > 0) reached(at);
    if (next >= world.route.size()) return false;
    *goal = world.route[next++];
    return true;
  };
  PriorMap map;
  map.path = drive(
      world.start, world.walls, planner, next_goal, [](double) { return false; }, kMaxCycles);
  reached(map.path.back());  // the last waypoint, or where the cycles ran out
  if (next < world.route.size())
    throw Error("world " + world.name +
                ": the mapping run ran out of control cycles before ROUTE waypoint " +
                std::to_string(next + 1) + " of " + std::to_string(world.route.size()));
  map.poses = discretise(map.path, config.map_poses);
  const Laser laser(config.laser);
  for (const Pose2& p : map.poses) map.scans.push_back(laser.scan(p, world.walls, {}, &rng));
  return map;
}

Trial localizationTrial(const World& world, const PriorMap& map, const TrialConfig& config,
                        std::uint64_t seed, int stream, int index) {
  std::mt19937_64 rng = streamRng(seed, stream, index);
  Trial trial;
  std::uniform_int_distribution<std::size_t> pick(0, map.path.size() - 1);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Boxes beside the mapping path, clear of the start and of the walls.
  for (int tries = 0;
       static_cast<int>(trial.obstacles.size()) < 4 * config.obstacles && tries < 1000; ++tries) {
    const Pose2& p = map.path[pick(rng)];
    const double side = (unit(rng) < 0.5 ? -1.0 : 1.0) * (0.3 + 0.4 * unit(rng));
    const Point2 c = p.t() + side * Point2(-std::sin(p.theta), std::cos(p.theta));
    if ((c - world.start.t()).norm() < 1.0) continue;
    if (distanceToSegments(c, world.walls) < config.obstacle_side / 2 + 0.1) continue;
    if (!trial.obstacles.empty() &&
        distanceToSegments(c, trial.obstacles) < config.obstacle_side + 2 * kRobotRadius)
      continue;
    for (const Segment& s : boxSegments(c, config.obstacle_side)) trial.obstacles.push_back(s);
  }
  std::vector<Segment> all = world.walls;
  all.insert(all.end(), trial.obstacles.begin(), trial.obstacles.end());

  const double target = config.min_length + (config.max_length - config.min_length) * unit(rng);
  const auto next_goal = [&](const Pose2& at, Point2* goal) {
    for (int tries = 0; tries < 1000; ++tries) {
      const Pose2& p = map.path[pick(rng)];
      const Point2 g = p.t() + config.waypoint_sigma * Point2(gauss(rng), gauss(rng));
      if ((g - at.t()).norm() < 1.5) continue;
      if (distanceToSegments(g, all) < kRobotRadius + 0.15) continue;
      *goal = g;
      trial.waypoints.push_back(g);
      return true;
    }
    return false;
  };
  const DynamicWindow planner(config.planner);
  const std::vector<Pose2> path = drive(
      world.start, all, planner, next_goal, [&](double length) { return length >= target; },
      kMaxCycles);
  trial.truth = discretise(path, config.poses, &trial.length);
  const Laser laser(config.laser);
  for (const Pose2& p : trial.truth)
    trial.scans.push_back(laser.scan(p, world.walls, trial.obstacles, &rng));
  trial.odometry = sampleOdometry(trial.truth, config, rng);
  return trial;
}

double stepSigma(double sigma, double d, double noise_distance) {
  return sigma * std::sqrt(d / noise_distance);
}

std::vector<Pose2> sampleOdometry(const std::vector<Pose2>& truth, const TrialConfig& config,
                                  std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Pose2> out;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    const Pose2 d = truth[i - 1].between(truth[i]);
    const double length = d.t().norm();
    const double sxy = stepSigma(config.sigma_xy, length, config.noise_distance);
    const double sth = stepSigma(config.sigma_theta, length, config.noise_distance);
    out.emplace_back(d.x + sxy * gauss(rng), d.y + sxy * gauss(rng),
                     wrapAngle(d.theta + sth * gauss(rng)));
  }
  return out;
}

}  // namespace hamal::moss
