// Trials: the mapping run and the localization trials of thesis sec. 5.5.
//
// Mapping run: the robot drives the world's ROUTE (the thesis' "manually
// driven" run) with the Dynamic Window planner; its trajectory, discretised
// into M poses, with a scan at each, is the prior map (sec. 5.3.1: each node
// keeps its pose and scan, the constraints are discarded). The map poses are
// the run's true poses: the mapping graph is taken as optimised to its
// ground truth, so map quality is not what the methods compete on.
//
// Localization trial: from the same known start, the robot drives to
// waypoints sampled around the mapping trajectory (a mapping pose plus
// Gaussian noise, redrawn until it is clear of walls and obstacles) with the
// Dynamic Window planner, among static boxes placed at random beside the
// mapping path, until it has driven a length drawn from [min, max]; the path
// is discretised into N poses equally spaced along its length.
//
// Odometry: between consecutive discretised poses, the true relative pose
// plus zero-mean Gaussian noise whose variance grows linearly with the
// distance d driven in that step: sigma_xy (each of x, y) and sigma_theta
// (sec. 5.5: 30 cm and 0.1 degree) are the standard deviations per
// `noise_distance` = 10 m, so a step draws sigma * sqrt(d / 10 m). Over a
// CORRIDOR trial (10-15 m) the dead-reckoning error is then about the
// thesis' 30 cm. Applied per step unscaled instead, 30 cm on steps of
// 0.2-0.8 m makes odometry nearly uninformative and the localization error
// metres whatever the map (tried: the full map's test RMSE was 1.8 m in
// CORRIDOR, 3 m and more in SQUARE).
// Everything is a function of the seed (and the trial's index), so a trial
// can be rebuilt anywhere from (config, seed, index).
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "apps/moss/dynamic_window.h"
#include "apps/moss/laser.h"
#include "apps/moss/world.h"

namespace hamal::moss {

struct TrialConfig {
  int map_poses = 21;                           // M
  int poses = 21;                               // N per localization trial
  double min_length = 10.0, max_length = 15.0;  // m
  int obstacles = 2;                            // boxes per localization trial
  double obstacle_side = 0.3;                   // m
  double waypoint_sigma = 0.4;                  // m, around a mapping pose
  double sigma_xy = 0.30;                       // m per noise_distance driven
  double sigma_theta = 0.1 * M_PI / 180.0;      // rad per noise_distance driven
  double noise_distance = 10.0;                 // m
  LaserConfig laser;
  DynamicWindowConfig planner;
};

// The scenario defaults of sec. 5.5.1 (CORRIDOR: M = N = 21, 10-15 m) and
// 5.5.2 (SQUARE: M = N = 204, 35-50 m); other worlds get CORRIDOR's.
TrialConfig scenarioConfig(const std::string& world_name);

struct Trial {
  std::vector<Pose2> truth;     // N poses
  std::vector<Pose2> odometry;  // N - 1 noisy relative poses, odometry[i]: truth[i] -> truth[i+1]
  std::vector<Scan> scans;      // N scans, in each pose's frame
  std::vector<Segment> obstacles;
  std::vector<Point2> waypoints;
  double length = 0.0;  // m driven
};

struct PriorMap {
  std::vector<Pose2> poses;  // M map nodes' global poses
  std::vector<Scan> scans;   // their scans
  std::vector<Pose2> path;   // the dense mapping path (for sampling waypoints)
};

PriorMap mappingRun(const World& world, const TrialConfig& config, std::uint64_t seed);
// Trial `index` of stream `stream` (0: training, 1: test).
Trial localizationTrial(const World& world, const PriorMap& map, const TrialConfig& config,
                        std::uint64_t seed, int stream, int index);

// The noisy odometry between consecutive poses of `truth` (see above).
// Per-step standard deviations for a step of length d: sigma * sqrt(d / D).
double stepSigma(double sigma, double d, double noise_distance);
std::vector<Pose2> sampleOdometry(const std::vector<Pose2>& truth, const TrialConfig& config,
                                  std::mt19937_64& rng);

// N poses equally spaced along `path`'s length.
std::vector<Pose2> discretise(const std::vector<Pose2>& path, int n, double* length = nullptr);

}  // namespace hamal::moss
