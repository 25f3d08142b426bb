// hamal_moss: MOSS (thesis ch. 5) from the command line.
//
//   hamal_moss world corridor|square|FILE     check a world and describe it
//   hamal_moss world --print corridor         print a built-in world's file
//   hamal_moss experiment --world corridor --sizes 1-20 --train 10 --test 10
//       --climbs 10 --steps 1000 --output results/moss/corridor
//   hamal_moss experiment --data intel.log --sizes 5,10,20 --output DIR   (a real log)
//
// See apps/moss/README.md for the figures' commands.
#include <gflags/gflags.h>

#include <cmath>
#include <iostream>
#include <thread>
#include <utility>

#include "apps/carmen/carmen_log_flags.h"
#include "apps/common/builtin_name.h"
#include "apps/common/cli.h"
#include "apps/moss/experiment.h"
#include "apps/moss/world.h"
#include "core/error.h"

DEFINE_string(world, "corridor",
              "corridor, square (any case) or a world file (apps/moss/README.md)");
DEFINE_string(sizes, "",
              "C values: 1-20 or 6,11,16,21 (default: 1-20 for corridor, "
              "6,11,16,21 for square)");
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
DEFINE_string(output, "", "experiment's output directory (rows.csv, map.csv, ...)");
HAMAL_FLAG_ALIAS(out, output);
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
DEFINE_string(objective, "rmse",
              "what MOSS minimises on the training trials: rmse (as the thesis reports) or "
              "sum_of_norms (eq. 5.3: the sum of the position errors' norms)");
DEFINE_bool(print, false, "world: print the built-in world's file text");
DEFINE_string(data, "",
              "experiment on a CARMEN log instead of --world: the first traversal is the "
              "map, later stretches revisiting it the trials (apps/moss/REAL_LOGS.md)");
DEFINE_double(revisit_gap, 20.0,
              "log: a pose revisits if within --revisit_radius of one driven this far before (m)");
DEFINE_double(node_spacing, 1.0, "log: metres of the mapping run's path between map nodes");
DEFINE_double(revisit_radius, 2.0,
              "log: a pose within this of one driven --revisit_gap before revisits (m)");
DEFINE_double(pose_step, 0.5, "log: keep a scan once the robot moved this far (m)");
DEFINE_double(pose_turn_deg, 15, "log: ... or turned this much (degrees)");
DEFINE_double(max_range, 8.0, "log: returns farther than this are dropped (m)");
DEFINE_double(train_fraction, 0.5, "log: the earlier share of the trials that trains MOSS");
DEFINE_string(odometry, "log",
              "log: the trials' odometry is the log's ODOM records (interpolated at the scans' "
              "times); synthetic: the reference motion plus simulated noise (an ablation)");
DEFINE_double(l2g_gate, 0,
              "refuse a scan match whose pose is farther from the prediction than this "
              "chi-square under dead reckoning's covariance (0: use every accepted match; "
              "11.34: 3 degrees of freedom at 99%)");
DEFINE_bool(calibrate_information, false,
            "divide the L2G information by how overconfident the full map's matches on the "
            "training trials are against the reference (chi-square median over 2.37)");
DEFINE_int32(climb, -1,
             "experiment: run only MOSS climb t (0..T-1) of every C into <out>/climbs/ and "
             "write no rows (a cluster's array task; a run without it picks the best)");
DEFINE_bool(verify_only, false,
            "experiment: verify (or start) --out against these parameters and stop");

int main(int argc, char** argv) {
  using namespace hamal;
  return apps::runMain("hamal_moss", [&] {
    const std::vector<std::string> args = apps::parseCommandLine(
        &argc, &argv,
        "MOSS map-node selection (thesis ch. 5).\n"
        "  hamal_moss world [--print] corridor|square|FILE\n"
        "  hamal_moss experiment --world W --sizes C.. --output DIR [--train S --test S' "
        "--climbs T --steps K]");
    Registry registry;
    apps::setUpRegistry(registry, apps::repeatedFlag(argc, argv, "plugin"));
    if (apps::printListings(registry)) return 0;
    if (args.empty()) throw Error("a command is needed: world or experiment (see --help)");
    if (args[0] == "world") {
      const std::string name = args.size() > 1 ? args[1] : FLAGS_world;
      if (FLAGS_print) {
        const std::string text = moss::builtinWorldText(name);
        if (text.empty()) throw Error("no built-in world '" + name + "' (corridor, square)");
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
      // A built-in world by its one spelling, so rows and resumed runs agree.
      c.source.world =
          moss::builtinWorldText(FLAGS_world).empty() ? FLAGS_world : apps::lowerCase(FLAGS_world);
      c.source.data = FLAGS_data;
      if (!c.source.data.empty()) {
        if (FLAGS_sizes.empty()) throw Error("--sizes is required with --data");
        c.source.log.revisit_gap = FLAGS_revisit_gap;
        c.source.log.node_spacing = FLAGS_node_spacing;
        c.source.log.revisit_radius = FLAGS_revisit_radius;
        c.source.log.scans.step = FLAGS_pose_step;
        c.source.log.scans.turn = FLAGS_pose_turn_deg * M_PI / 180;
        c.source.log.max_range = FLAGS_max_range;
        c.source.log.train_fraction = FLAGS_train_fraction;
        c.source.log.odometry = moss::parseLogOdometry(FLAGS_odometry);
        if (FLAGS_poses > 0) c.source.log.trial_poses = FLAGS_poses;
        c.source.log.seed = FLAGS_seed;
        c.source.log.validate();
        c.source.read =
            carmen::readOptionsFromFlags();  // --max_time_reversal, --no_return_range, ...
      }
      const bool square = c.source.data.empty() && moss::loadWorld(c.source.world).name == "square";
      c.sizes =
          moss::parseSizes(FLAGS_sizes.empty() ? (square ? "6,11,16,21" : "1-20") : FLAGS_sizes);
      c.methods = apps::splitList(FLAGS_methods, ',');
      c.train = FLAGS_train;
      c.test = FLAGS_test;
      c.climbs = FLAGS_climbs;
      c.steps = FLAGS_steps;
      c.seed = FLAGS_seed;
      c.run.threads =
          FLAGS_threads > 0 ? FLAGS_threads : std::max(1u, std::thread::hardware_concurrency());
      c.localizer.backend = FLAGS_backend;
      c.localizer.objective = moss::parseObjective(FLAGS_objective);
      if (!(FLAGS_l2g_gate >= 0) || !std::isfinite(FLAGS_l2g_gate))
        throw Error("--l2g_gate must be a chi-square >= 0 (0: no gate)");
      c.localizer.gate_chi2 = FLAGS_l2g_gate;
      c.matches.calibrate_information = FLAGS_calibrate_information;
      c.source.map_poses = FLAGS_map_poses;
      c.source.poses = FLAGS_poses;
      c.run.out = FLAGS_output;
      c.reuse = FLAGS_reuse;
      try {
        c.matches.matcher.information = moss::parseInformation(FLAGS_information);
      } catch (const Error& e) {
        throw Error(std::string("--information: ") + e.what());
      }
      c.matches.censi_sigma = FLAGS_censi_sigma;
      if (FLAGS_climb < -1)
        throw Error("--climb " + std::to_string(FLAGS_climb) +
                    ": a climb index 0..T-1 (-1: every climb)");
      c.run.climb = FLAGS_climb;
      c.run.verify_only = FLAGS_verify_only;
      moss::runExperiment(c, registry, std::cerr);
      return 0;
    }
    throw Error("unknown command '" + args[0] + "' (world, experiment)");
  });
}
