// hamal_moss: MOSS (thesis ch. 5) from the command line.
//
//   hamal_moss world CORRIDOR|SQUARE|FILE     check a world and describe it
//   hamal_moss world --print CORRIDOR         print a built-in world's file
//   hamal_moss experiment --world CORRIDOR --sizes 1-20 --train 10 --test 10
//       --climbs 10 --steps 1000 --out results/moss/corridor
//
// See apps/moss/README.md for the figures' commands.
#include <gflags/gflags.h>

#include <iostream>
#include <thread>
#include <utility>

#include "apps/common/cli.h"
#include "apps/moss/experiment.h"
#include "apps/moss/world.h"
#include "core/error.h"

DEFINE_string(world, "CORRIDOR", "CORRIDOR, SQUARE or a world file (apps/moss/README.md)");
DEFINE_string(sizes, "",
              "C values: 1-20 or 6,11,16,21 (default: 1-20 for CORRIDOR, "
              "6,11,16,21 for SQUARE)");
DEFINE_string(methods, "equidistant,ssm,moss", "node-selection methods to run");
DEFINE_int32(train, 10, "S, training localization trials (MOSS learns from them)");
DEFINE_int32(test, 10, "test localization trials (every method is scored on them)");
DEFINE_int32(climbs, 10, "T, MOSS hill climbs");
DEFINE_int32(steps, 1000, "K, steps per MOSS hill climb");
DEFINE_uint64(seed, 1, "seed of the mapping run, the trials and the climbs");
DEFINE_int32(threads, 0, "threads for MOSS' climbs (0: the machine's cores)");
DEFINE_string(backend, "aprilsam", "back-end that solves each localization graph (spec)");
DEFINE_int32(map_poses, 0, "M, map nodes (0: the scenario's, 21 or 204)");
DEFINE_int32(poses, 0, "N, poses per trial (0: the scenario's, 21 or 204)");
DEFINE_string(out, "", "experiment's output directory (rows.csv, map.csv, ...)");
DEFINE_bool(reuse, true,
            "MOSS: localize only the training trials a swap can change (false: all of "
            "them; same selections)");
DEFINE_string(information, "hessian",
              "L2G information from a scan match: hessian (J^T J / sigma^2) or censi "
              "(Censi's closed-form covariance, apps/moss/icp_covariance.h)");
DEFINE_double(censi_sigma, 0,
              "sigma_d (m) that --information=censi assumes for the live ranges (0: the "
              "laser's range noise, 2 cm); larger values also cover what the noise model "
              "leaves out, see apps/moss/README.md");
DEFINE_bool(print, false, "world: print the built-in world's file text");

int main(int argc, char** argv) {
  using namespace hamal;
  return apps::runMain("hamal_moss", [&] {
    const std::vector<std::string> args = apps::parseCommandLine(
        &argc, &argv,
        "MOSS map-node selection (thesis ch. 5).\n"
        "  hamal_moss world [--print] CORRIDOR|SQUARE|FILE\n"
        "  hamal_moss experiment --world W --sizes C.. --out DIR [--train S --test S' "
        "--climbs T --steps K]");
    Registry registry;
    apps::setUpRegistry(registry, apps::repeatedFlag(argc, argv, "plugin"));
    if (apps::printListings(registry)) return 0;
    if (args.empty()) throw Error("a command is needed: world or experiment (see --help)");
    if (args[0] == "world") {
      const std::string name = args.size() > 1 ? args[1] : FLAGS_world;
      if (FLAGS_print) {
        const std::string text = moss::builtinWorldText(name);
        if (text.empty()) throw Error("no built-in world '" + name + "' (CORRIDOR, SQUARE)");
        std::cout << text;
        return 0;
      }
      std::cout << moss::describeWorld(moss::loadWorld(name)) << "\n";
      return 0;
    }
    if (args[0] == "experiment") {
      // Counts: 0 means "the default" for some, a negative one is a typo.
      for (const auto& [flag, value] : {std::pair<const char*, int>{"train", FLAGS_train},
                                        {"test", FLAGS_test},
                                        {"climbs", FLAGS_climbs},
                                        {"steps", FLAGS_steps},
                                        {"threads", FLAGS_threads},
                                        {"map_poses", FLAGS_map_poses},
                                        {"poses", FLAGS_poses}})
        if (value < 0)
          throw Error("--" + std::string(flag) + " " + std::to_string(value) +
                      ": must be a non-negative integer");
      moss::ExperimentConfig c;
      c.world = FLAGS_world;
      const bool square = moss::loadWorld(c.world).name == "SQUARE";
      c.sizes =
          moss::parseSizes(FLAGS_sizes.empty() ? (square ? "6,11,16,21" : "1-20") : FLAGS_sizes);
      c.methods = apps::splitList(FLAGS_methods, ',');
      c.train = FLAGS_train;
      c.test = FLAGS_test;
      c.climbs = FLAGS_climbs;
      c.steps = FLAGS_steps;
      c.seed = FLAGS_seed;
      c.threads =
          FLAGS_threads > 0 ? FLAGS_threads : std::max(1u, std::thread::hardware_concurrency());
      c.localizer.backend = FLAGS_backend;
      c.map_poses = FLAGS_map_poses;
      c.poses = FLAGS_poses;
      c.out = FLAGS_out;
      c.reuse = FLAGS_reuse;
      try {
        c.matcher.information = moss::parseInformation(FLAGS_information);
      } catch (const Error& e) {
        throw Error(std::string("--information: ") + e.what());
      }
      c.censi_sigma = FLAGS_censi_sigma;
      moss::runExperiment(c, registry, std::cerr);
      return 0;
    }
    throw Error("unknown command '" + args[0] + "' (world, experiment)");
  });
}
