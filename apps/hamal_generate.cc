// hamal_generate: writes a synthetic Manhattan world (apps/generator/
// manhattan_world.h, after Olson's M3500, the thesis' benchmark world) as a
// g2o file, and optionally its ground truth, so that benchmarks and tests
// need no download and can be made as large as wanted.
#include <gflags/gflags.h>

#include <iostream>

#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/stopwatch.h"

DEFINE_uint64(poses, 1000, "number of poses");
DEFINE_uint64(seed, 1, "random seed: the same seed gives the same world on every platform");
DEFINE_double(sigma_xy, 0.05, "odometry and loop-closure noise on x and y, metres (std dev)");
DEFINE_double(sigma_theta, 0.01, "odometry and loop-closure noise on theta, radians (std dev)");
DEFINE_double(loop_closure_rate, 0.08,
              "probability of a loop closure to each earlier pose within the radius");
DEFINE_double(loop_closure_radius, 1.5,
              "loop closures reach poses this close, metres (grid step 1 m)");
DEFINE_uint64(min_loop_gap, 10, "loop closures only to poses at least this many steps back");
DEFINE_double(turn_probability, 0.3, "probability of a +-90 degree turn at each intersection");
DEFINE_uint64(world_size, 0, "side of the square world in grid steps; 0: ceil(sqrt(poses))");
DEFINE_double(pose_closure_probability, 0,
              "sparse loop closures: when > 0, each pose makes at most one closure, with this "
              "probability, to one pose in reach (--loop_closure_rate is then unused)");
DEFINE_uint64(first_loop_closure, 0, "long drift: no loop closure at the poses before this one");
DEFINE_double(odometry_sigma_xy, 0, "odometry's own noise on x and y, metres; 0: --sigma_xy");
DEFINE_double(odometry_sigma_theta, 0, "odometry's own noise on theta, radians; 0: --sigma_theta");
DEFINE_uint64(odometry_gaps, 0,
              "poses, evenly spaced, with no odometry link to their predecessor (joined to the "
              "pose two back by a loop closure instead)");
DEFINE_uint64(components, 1,
              "disconnected runs of consecutive poses, each fixed (FIX) at its true first pose");
DEFINE_string(output, "", "the graph: g2o file with odometry-composed vertices and EDGE_SE2 edges");
DEFINE_string(truth, "", "optional g2o file with the ground-truth vertices (and the same edges)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "writes a synthetic Manhattan-world pose graph (after Olson's M3500).\n\n"
    "  hamal_generate --poses 3500 --seed 7 --output world.g2o --truth truth.g2o\n"
    "  hamal_generate --poses 2000 --pose_closure_probability 0.05 --first_loop_closure 500 \\\n"
    "      --odometry_gaps 2 --components 2 --output judging.g2o";

int generate(const std::vector<std::string>& plugins, const std::vector<std::string>& positional) {
  Registry registry;
  setUpRegistry(registry, plugins);
  if (printListings(registry)) return 0;
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_output.empty()) throw Error("no output file: give --output world.g2o (see --help)");
  checkOutputPaths({{"output", FLAGS_output}, {"truth", FLAGS_truth}});
  ManhattanWorldOptions options;
  options.poses = FLAGS_poses;
  options.seed = FLAGS_seed;
  options.noise.sigma_xy = FLAGS_sigma_xy;
  options.noise.sigma_theta = FLAGS_sigma_theta;
  options.loop_closures.rate = FLAGS_loop_closure_rate;
  options.loop_closures.radius = FLAGS_loop_closure_radius;
  options.loop_closures.min_gap = FLAGS_min_loop_gap;
  options.turn_probability = FLAGS_turn_probability;
  options.world_size = FLAGS_world_size;
  options.loop_closures.pose_probability = FLAGS_pose_closure_probability;
  options.loop_closures.first_pose = FLAGS_first_loop_closure;
  options.noise.odometry_sigma_xy = FLAGS_odometry_sigma_xy;
  options.noise.odometry_sigma_theta = FLAGS_odometry_sigma_theta;
  options.odometry_gaps = FLAGS_odometry_gaps;
  options.components = FLAGS_components;

  Stopwatch watch;
  const ManhattanWorld world = generateManhattanWorld(options);
  const double generated = watch.lap();
  writeG2o(FLAGS_output, world.graph.initial, world.graph.factors, world.graph.fixed);
  if (!FLAGS_truth.empty())
    writeG2o(FLAGS_truth, world.truth, world.graph.factors, world.graph.fixed);
  std::cout << "hamal_generate: " << options.poses << " poses, " << world.odometry_edges
            << " odometry edges, " << world.loop_closures << " loop closures, world "
            << world.world_size << " x " << world.world_size << " m, "
            << world.component_starts.size() << " component(s), " << world.gaps.size()
            << " odometry gap(s), seed " << options.seed << " (generated in " << generated
            << " s, written in " << watch.lap() << " s)\n"
            << "  graph: " << FLAGS_output << "\n";
  if (!FLAGS_truth.empty()) std::cout << "  truth: " << FLAGS_truth << "\n";
  return 0;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_generate", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::generate(plugins, positional);
  });
}
