// hamal_spoil: spoils a pose graph with false loop closures as the Vertigo
// datasets were made (false_loop_closures.h), for the robust benchmark
// (apps/robust/README.md). Writes the spoiled graph as g2o and, beside it,
// the list of its false edges (false_edge_list.h).
#include <gflags/gflags.h>

#include <iostream>

#include "apps/common/cli.h"
#include "apps/robust/false_edge_list.h"
#include "apps/robust/false_loop_closures.h"
#include "core/error.h"
#include "core/graph_io.h"

DEFINE_string(data, "", "clean graph to spoil (g2o, TORO or GTSAM file, as hamal_solve reads)");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_string(output, "",
              "spoiled graph to write (g2o); its false-edge list is written to OUTPUT.false");
HAMAL_FLAG_ALIAS(out, output);
DEFINE_uint64(outliers, 100, "N: false loop closures to add, in all (0 writes the clean graph)");
DEFINE_string(policy, "random", "random | local | random-group | local-group (Vertigo's policies)");
DEFINE_uint64(seed, 1, "seed: the same seed, data and options give the same file on any platform");
DEFINE_uint64(group_size, 10, "edges per group in the group policies (Vertigo's experiments: 10)");
DEFINE_uint64(local_window, 20,
              "local policies: largest id gap j - i of a false edge (Vertigo: 20)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "adds N false loop closures to a pose graph, the way the Vertigo datasets were made.\n\n"
    "  hamal_spoil --data ../shared/data/M3500.toro --outliers 100 --policy random --seed 1 \\\n"
    "              --output M3500-random-100.g2o\n\n"
    "A false edge joins pose i to pose j >= i + 2 with a near-identity measurement\n"
    "(dx, dy ~ N(0, 0.3 m), dtheta ~ N(0, 10 deg)) and the information of the dataset's\n"
    "first loop closure; no pose pair gets two edges. The spoiled graph is the clean one\n"
    "(vertices and factors in their order) followed by the false edges; OUTPUT.false lists\n"
    "them by factor index. More false edges than free pose pairs is an error.";

int spoil(const std::vector<std::string>& plugins, const std::vector<std::string>& positional) {
  Registry registry;
  setUpRegistry(registry, plugins);
  if (printListings(registry)) return 0;
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_data.empty()) throw Error("--data is required (the clean graph)");
  if (FLAGS_output.empty()) throw Error("--output is required (the spoiled graph to write)");
  checkOutputPaths({{"output", FLAGS_output}, {"output", falseEdgesPath(FLAGS_output)}},
                   {{"data", FLAGS_data}});
  SpoilOptions options;
  options.outliers = FLAGS_outliers;
  options.policy = parseSpoilPolicy(FLAGS_policy);
  options.seed = FLAGS_seed;
  options.group_size = FLAGS_group_size;
  options.local_window = FLAGS_local_window;

  const Graph clean = readGraph(FLAGS_data, registry, parseFormat(FLAGS_format));
  const SpoiledGraph spoiled = spoilGraph(clean, options);
  FalseEdgeList list;
  list.spoiling = {{"source", FLAGS_data},
                   {"policy", spoilPolicyName(options.policy)},
                   {"outliers", std::to_string(options.outliers)},
                   {"seed", std::to_string(options.seed)},
                   {"group_size", std::to_string(options.group_size)},
                   {"local_window", std::to_string(options.local_window)},
                   {"graph_factors", std::to_string(spoiled.graph.factors.size())}};
  list.edges = spoiled.false_edges;
  // Both are written whole before either is put in place (runMain's
  // OutputBatch), and the list is renamed last: a list beside a graph means
  // the pair is complete; a failed run leaves the old pair as it was.
  writeG2o(FLAGS_output, spoiled.graph.initial, spoiled.graph.factors, spoiled.graph.fixed);
  writeFalseEdges(falseEdgesPath(FLAGS_output), list);
  std::cout << FLAGS_output << ": " << clean.factors.size() << " factors of " << FLAGS_data << " + "
            << spoiled.false_edges.size() << " false loop closures ("
            << spoilPolicyName(options.policy) << ", seed " << options.seed
            << "); list: " << falseEdgesPath(FLAGS_output) << "\n";
  return 0;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_spoil", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::spoil(plugins, positional);
  });
}
