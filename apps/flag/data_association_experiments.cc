// The dynamic- and static-obstacle trials of thesis sec. 4.4.3
// (data_association_experiments.h).
#include "apps/flag/data_association_experiments.h"

#include <cmath>
#include <random>

#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMeasurementSigma = 0.10;  // thesis sec. 4.4.3.1 and 4.4.3.2
constexpr double kPersonSigma = 0.01;       // thesis fig. 4.7

// A measurement of `point` seen from `pose` with isotropic point noise of
// `sigma`. The detector cannot tell a person from a corner, so its stated
// range-bearing sigmas are the sensor's (`stated` at that range) whatever
// the noise was.
Detection pointDetection(const Pose2& pose, const Point2& point, double sigma, Source source,
                         std::mt19937_64& rng, double stated = kMeasurementSigma) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double ex = n01(rng), ey = n01(rng);
  const Point2 noisy = pose.transformTo(point + sigma * Point2(ex, ey));
  Detection d;
  d.range = noisy.norm();
  d.bearing = std::atan2(noisy.y(), noisy.x());
  d.range_sigma = stated;
  d.bearing_sigma = stated / std::max(d.range, 0.5);
  d.source = source;
  return d;
}

// Poses along the x axis, 0.5 m apart, with the thesis' odometry noise.
Recording straightDrive(int poses, std::mt19937_64& rng) {
  const SimulatorOptions sim;
  Recording rec;
  rec.odom_sigma_x = sim.stated.odom_sigma_x;
  rec.odom_sigma_y = sim.stated.odom_sigma_y;
  rec.odom_sigma_theta = sim.stated.odom_sigma_theta;
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int i = 0; i < poses; ++i) {
    RecordedStep s;
    s.truth = Pose2(0.5 * i, 0.0, 0.0);
    s.time = 0.25 * i;
    if (i > 0) {
      s.distance = 0.5;
      const Eigen::Vector3d sig = odometrySigmas(sim.noise.odom_sigma_x, sim.noise.odom_sigma_y,
                                                 sim.noise.odom_sigma_theta, 0.5);
      const double ex = n01(rng), ey = n01(rng), et = n01(rng);
      s.odometry = Pose2(0.5 + sig[0] * ex, sig[1] * ey, sig[2] * et);
    }
    rec.steps.push_back(s);
  }
  return rec;
}

LandmarkLabel labelled(std::uint64_t id, const Point2& truth, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double ex = n01(rng), ey = n01(rng);
  return {id, truth + sigma * Point2(ex, ey), {}};
}

// A ray-cast landmark: the bend of an L, a 1 m wall along the drive ending
// at the corner and one 1 m back toward the drive (y = 0).
void addLCorner(FloorPlan* plan, std::uint64_t id, const Point2& c, double landmark_sigma,
                std::mt19937_64& rng) {
  const Point2 toward(0, c.y() > 0 ? -1.0 : 1.0);
  plan->walls.push_back({c - Point2(1, 0), c});
  plan->walls.push_back({c, c + toward});
  plan->corners.push_back({id, c, labelled(id, c, landmark_sigma, rng).label});
}

// A hall [x0, x1] x [y0, y1] around a scene, its corners out of the sensor's range.
void addHall(FloorPlan* plan, double x0, double y0, double x1, double y1) {
  const Point2 hall[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int k = 0; k < 4; ++k) plan->walls.push_back({hall[k], hall[(k + 1) % 4]});
}

// The ray-cast scenes' sensor range (the hand-made static trial's).
constexpr double kSceneRange = 4.0;

TrialResult grade(const std::vector<LandmarkLabel>& labels, const Recording& rec,
                  const FlagOptions& options, const Registry& registry) {
  const FlagRun run = runFlag(labels, rec, options, registry);
  TrialResult t;
  t.last_error = run.flag.last_position;
  t.mean_error = run.flag.position;
  t.stats = run.stats;
  t.mixtures = run.factors.mixtures;
  t.null_active = run.factors.null_active;
  t.ok = run.ok;
  return t;
}

}  // namespace

Recording dynamicObstacleRecording(std::uint64_t seed, std::vector<LandmarkLabel>* labels,
                                   double landmark_sigma) {
  std::mt19937_64 rng(seed);
  const Point2 landmark(2.5, 3.0);
  Recording rec = straightDrive(10, rng);
  labels->assign(1, labelled(0, landmark, landmark_sigma, rng));
  // The person's line passes the landmark at a random side distance of
  // 10..40 cm in a random direction; 10 positions 11 cm apart span 1 m.
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double offset = 0.1 + 0.3 * u01(rng), heading = 2 * kPi * u01(rng);
  const Point2 dir(std::cos(heading), std::sin(heading));
  const Point2 centre = landmark + offset * Point2(-dir.y(), dir.x());
  for (std::size_t i = 0; i < rec.steps.size(); ++i) {
    RecordedStep& s = rec.steps[i];
    s.detections.push_back(
        pointDetection(s.truth, landmark, kMeasurementSigma, {Source::kCorner, 0}, rng));
    const Point2 person = centre + dir * (-0.5 + 0.11 * double(i));
    s.detections.push_back(
        pointDetection(s.truth, person, kPersonSigma, {Source::kPerson, 0}, rng));
  }
  return rec;
}

Recording staticObstacleRecording(std::uint64_t seed, double radius,
                                  std::vector<LandmarkLabel>* labels, double landmark_sigma,
                                  double stated_sigma) {
  if (!(radius >= 0)) throw Error("static obstacle: radius must be >= 0");
  if (!(stated_sigma > 0)) throw Error("static obstacle: the stated sigma must be > 0");
  std::mt19937_64 rng(seed);
  const std::vector<Point2> landmarks = {{1.5, 2.0}, {4.0, -2.0}, {6.5, 2.0}, {9.0, -2.0}};
  Recording rec = straightDrive(20, rng);
  labels->clear();
  for (std::size_t k = 0; k < landmarks.size(); ++k)
    labels->push_back(labelled(k, landmarks[k], landmark_sigma, rng));
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double rho = radius * std::sqrt(u01(rng)), phi = 2 * kPi * u01(rng);
  const Point2 obstacle = landmarks.back() + rho * Point2(std::cos(phi), std::sin(phi));
  constexpr double kRange = 4.0;
  for (RecordedStep& s : rec.steps) {
    for (std::size_t k = 0; k < landmarks.size(); ++k) {
      const bool last = k + 1 == landmarks.size();
      const Point2 seen = last ? obstacle : landmarks[k];
      if ((seen - s.truth.t()).norm() > kRange) continue;
      const Source source = last ? Source{Source::kObject, 0} : Source{Source::kCorner, k};
      s.detections.push_back(
          pointDetection(s.truth, seen, kMeasurementSigma, source, rng, stated_sigma));
    }
  }
  return rec;
}

FloorPlan dynamicObstaclePlan(std::uint64_t seed, double landmark_sigma, double robot_speed) {
  if (!(robot_speed > 0) || !std::isfinite(robot_speed))
    throw Error("dynamic obstacle: the robot's speed must be > 0");
  std::mt19937_64 rng(seed);
  FloorPlan plan;
  plan.name = "dynamic obstacle";
  const Point2 landmark(2.5, 3.0);
  // A V of two 1 m walls whose inside faces the whole drive, so that the
  // landmark is in view at every pose, as in the hand-made trial.
  for (double side : {-1.0, 1.0})
    plan.walls.push_back({landmark, landmark + std::sqrt(0.5) * Point2(side, -1.0)});
  plan.corners.push_back({0, landmark, labelled(0, landmark, landmark_sigma, rng).label});
  // As the hand-made trial: a line 10..40 cm to one side of the landmark in
  // a random direction, 11 cm per pose of the robot's (0.5 m apart).
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double offset = 0.1 + 0.3 * u01(rng), heading = 2 * kPi * u01(rng);
  const Point2 dir(std::cos(heading), std::sin(heading));
  const Point2 centre = landmark + offset * Point2(-dir.y(), dir.x());
  plan.people.push_back({centre - 0.5 * dir, centre + 0.5 * dir, 0.0, 0.11 * robot_speed / 0.5});
  addHall(&plan, -3, -4, 7.5, 4.5);
  plan.path = {{0, 0}, {4.5, 0}};
  plan.validate("dynamic obstacle");
  return plan;
}

FloorPlan staticObstaclePlan(std::uint64_t seed, double radius, double landmark_sigma) {
  if (!(radius >= 0) || !std::isfinite(radius)) throw Error("static obstacle: radius must be >= 0");
  std::mt19937_64 rng(seed);
  FloorPlan plan;
  plan.name = "static obstacle";
  const std::vector<Point2> landmarks = {{1.5, 2.0}, {4.0, -2.0}, {6.5, 2.0}, {9.0, -2.0}};
  for (std::size_t k = 0; k < landmarks.size(); ++k)
    addLCorner(&plan, k, landmarks[k], landmark_sigma, rng);
  // The corner's open side, seen from the drive: x below it, y toward the drive.
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double rho = radius * std::sqrt(u01(rng)), phi = kPi / 2 + kPi / 2 * u01(rng);
  const Point2 obstacle = landmarks.back() + rho * Point2(std::cos(phi), std::sin(phi));
  plan.objects.push_back({obstacle, 1.7, static_cast<std::int64_t>(landmarks.size() - 1)});
  addHall(&plan, -3, -4, 13, 4);
  plan.path = {{0, 0}, {9.5, 0}};
  plan.validate("static obstacle");
  return plan;
}

TrialResult dynamicObstacleTrial(std::uint64_t seed, const FlagOptions& options,
                                 const Registry& registry) {
  std::vector<LandmarkLabel> labels;
  const Recording rec = dynamicObstacleRecording(seed, &labels, options.landmarks.sigma);
  return grade(labels, rec, options, registry);
}

TrialResult staticObstacleTrial(std::uint64_t seed, double radius, const FlagOptions& options,
                                const Registry& registry, double stated_sigma) {
  std::vector<LandmarkLabel> labels;
  const Recording rec =
      staticObstacleRecording(seed, radius, &labels, options.landmarks.sigma, stated_sigma);
  return grade(labels, rec, options, registry);
}

TrialResult staticObstacleScanTrial(std::uint64_t seed, double radius, const FlagOptions& options,
                                    SimulatorOptions simulator, const Registry& registry) {
  const FloorPlan plan = staticObstaclePlan(seed, radius, options.landmarks.sigma);
  simulator.seed = seed;
  simulator.sensor_range = kSceneRange;
  return grade(labelsOf(plan), simulate(plan, simulator), options, registry);
}

TrialResult dynamicObstacleScanTrial(std::uint64_t seed, const FlagOptions& options,
                                     SimulatorOptions simulator, const Registry& registry) {
  const FloorPlan plan = dynamicObstaclePlan(seed, options.landmarks.sigma, simulator.speed);
  simulator.seed = seed;
  simulator.sensor_range = kSceneRange;
  return grade(labelsOf(plan), simulate(plan, simulator), options, registry);
}

}  // namespace hamal::flag
