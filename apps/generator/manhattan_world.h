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
// Deterministic for a seed on every platform: std::mt19937_64 is specified
// bit for bit by the standard, and the uniform and normal samples are made
// here (53-bit uniforms, Box-Muller) instead of by std::*_distribution, whose
// algorithms differ between standard libraries.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/graph.h"
#include "core/values.h"

namespace hamal::apps {

struct ManhattanWorldOptions {
  std::size_t poses = 1000;
  std::uint64_t seed = 1;
  double sigma_xy = 0.05;     // noise of each translation component, metres (per axis)
  double sigma_theta = 0.01;  // noise of the rotation, radians
  // Probability that a loop closure is made to each earlier pose within the
  // radius (and at least min_loop_gap steps back).
  double loop_closure_rate = 0.08;
  double loop_closure_radius = 1.5;  // metres (the grid step is 1 m)
  std::size_t min_loop_gap = 10;     // closures to the last few poses are odometry's job
  double turn_probability = 0.3;     // at each intersection, else straight on
  // Side of the square world in grid steps; 0 picks ceil(sqrt(poses)), about
  // one visit per intersection.
  std::size_t world_size = 0;
};

struct ManhattanWorld {
  // Odometry and loop-closure BetweenFactors (isotropic xy information,
  // written as g2o EDGE_SE2), and initial values composed from the noisy
  // odometry, as in M3500.toro's vertices.
  Graph graph;
  Values truth;  // X(i) for every pose
  std::size_t odometry_edges = 0;
  std::size_t loop_closures = 0;
  std::size_t world_size = 0;  // the side actually used
};

// Throws hamal::Error on options out of range (fewer than 2 poses, a sigma
// that is not positive, a rate outside [0, 1], a negative radius).
ManhattanWorld generateManhattanWorld(const ManhattanWorldOptions& options);

}  // namespace hamal::apps
