// ManhattanWorld: a synthetic 2D pose graph in the manner of Olson's M3500
// (Olson, Leonard, Teller 2006; the thesis' benchmark world, sec. 3.5.1): a
// robot drives a square grid of streets in unit steps, turning +-90 degrees
// at random at intersections and never leaving the world; odometry and loop
// closures are rigid-body betweens (factors/between_factor.h) with Gaussian
// noise; the ground truth is kept.
//
// It lets the benchmarks and tests run with no download, at any size: the
// world's side grows as sqrt(poses), so the density of revisits (and of loop
// closures per pose) stays about the same from 10^2 to 10^6 poses, and the
// loop-closure search uses a spatial hash grid (O(N) overall, not O(N^2)).
//
// The shapes that break robust loop-closure models on real graphs, each an
// option (off by default, so the default world is unchanged; all can be
// combined; apps/robust/README.md, "Judging worlds"):
//   sparse loop closures: loop_closures.pose_probability > 0 makes at most
//     one closure per pose, with that probability, to one candidate drawn
//     uniformly among those in reach (MIT's 20 closures in 800 poses);
//   long drift before the first closure: no closure at the poses before
//     loop_closures.first_pose, and odometry noise of its own
//     (noise.odometry_sigma_xy/_theta), so the start is far off when the
//     first loop closes;
//   odometry gaps: odometry_gaps poses, evenly spaced, have no odometry
//     link to their predecessor; pose g is joined to pose g-2 by a loop
//     closure instead (a relocalisation across the gap), so the graph stays
//     connected by closures alone there;
//   several components: the poses are split into `components` runs of
//     consecutive ids with no factor between runs; the first pose of each
//     run is fixed (a g2o FIX line, Graph::fixed) at its true pose, and its
//     run's initial values are composed from there.
//
// Deterministic for a seed on every platform: std::mt19937_64 is specified
// bit for bit by the standard, and the uniform and normal samples are made
// here (53-bit uniforms, Box-Muller) instead of by std::*_distribution, whose
// algorithms differ between standard libraries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/graph.h"
#include "core/values.h"

namespace hamal::apps {

struct ManhattanWorldOptions {
  // The betweens' Gaussian noise.
  struct Noise {
    double sigma_xy = 0.05;     // noise of each translation component, metres (per axis)
    double sigma_theta = 0.01;  // noise of the rotation, radians
    // The odometry's own noise (stated in its information); 0: sigma_xy / sigma_theta.
    double odometry_sigma_xy = 0;
    double odometry_sigma_theta = 0;
  };
  // Which revisits make loop closures.
  struct LoopClosures {
    // Probability that a loop closure is made to each earlier pose within the
    // radius (and at least min_gap steps back).
    double rate = 0.08;
    double radius = 1.5;       // metres (the grid step is 1 m)
    std::size_t min_gap = 10;  // closures to the last few poses are odometry's job
    // Sparse loop closures: when > 0, each pose makes at most one closure,
    // with this probability, to one candidate in reach (rate is then
    // unused).
    double pose_probability = 0;
    std::size_t first_pose = 0;  // no loop closure at the poses before this one
  };
  std::size_t poses = 1000;
  std::uint64_t seed = 1;
  Noise noise;
  LoopClosures loop_closures;
  double turn_probability = 0.3;  // at each intersection, else straight on
  // Side of the square world in grid steps; 0 picks ceil(sqrt(poses)), about
  // one visit per intersection.
  std::size_t world_size = 0;
  std::size_t odometry_gaps = 0;  // poses without an odometry link to their predecessor
  std::size_t components = 1;     // disconnected runs of consecutive poses, each fixed at its start
};

struct ManhattanWorld {
  // Odometry and loop-closure BetweenFactors (isotropic xy information,
  // written as g2o EDGE_SE2), and initial values composed from the noisy
  // odometry, as in M3500.toro's vertices.
  Graph graph;
  Values truth;  // X(i) for every pose
  std::size_t odometry_edges = 0;
  std::size_t loop_closures = 0;
  std::size_t world_size = 0;                 // the side actually used
  std::vector<std::size_t> gaps;              // poses with no odometry to their predecessor
  std::vector<std::size_t> component_starts;  // first pose of each component (0 first)
};

// Throws hamal::Error on options out of range (fewer than 2 poses, a sigma
// that is not positive, a rate or probability outside [0, 1], a negative
// radius, components of fewer than 4 poses, no room for a gap at least 2
// poses into its component).
ManhattanWorld generateManhattanWorld(const ManhattanWorldOptions& options);

}  // namespace hamal::apps
