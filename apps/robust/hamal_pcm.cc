// hamal_pcm: Pairwise Consistency Maximization (Mangelson et al., ICRA 2018;
// backends/robust/pairwise_consistency_maximization.h) on the loop closures
// of a pose graph on its own, batch or incremental, with its cost and, for
// a graph hamal_spoil wrote, how its decisions grade against the false-edge
// list (apps/robust/README.md).
#include <gflags/gflags.h>

#include <algorithm>
#include <fstream>
#include <iostream>

#include "apps/common/cli.h"
#include "apps/robust/false_edge_list.h"
#include "backends/robust/incremental_pairwise_consistency_maximization.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/stopwatch.h"

DEFINE_string(data, "", "pose graph (g2o, TORO or GTSAM); a spoiled one's DATA.false grades it");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_string(options, "", "PCM options k=v,k=v (pcm_probability, pcm_threshold, ...; see --help)");
DEFINE_bool(incremental, false,
            "incremental PCM, closures in the order of their later pose (the thesis protocol's)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "runs Pairwise Consistency Maximization on the loop closures of a pose graph.\n\n"
    "  hamal_pcm --data M3500-random-1000.g2o\n"
    "  hamal_pcm --data M3500-random-1000.g2o --incremental --options pcm_window=20,pcm_sample=20\n"
    "  hamal_pcm --data city10000-random-1000.g2o --options pcm_clique_seconds=60\n\n"
    "Odometry is every factor between consecutive pose ids; loop closures are the\n"
    "other pose-pose factors. Prints the consistency graph's size and time, the\n"
    "clique search's time and whether it was exact, and, when DATA.false exists,\n"
    "the false edges accepted and true loop closures rejected.";

int run(const std::vector<std::string>& plugins, const std::vector<std::string>& positional) {
  Registry registry;
  setUpRegistry(registry, plugins);
  if (printListings(registry)) return 0;
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_data.empty()) throw Error("--data is required");
  const BackendSpec spec =
      BackendSpec::parse(FLAGS_options.empty() ? "pcm" : "pcm:" + FLAGS_options);
  const robust::PcmOptions options = robust::pcmOptionsFrom(
      Options("hamal_pcm --options", robust::pcmOptionSpecs(), spec.options));
  const Graph graph = readGraph(FLAGS_data, registry, parseFormat(FLAGS_format));
  std::vector<bool> is_false_factor(graph.factors.size(), false);
  const bool graded = static_cast<bool>(std::ifstream(falseEdgesPath(FLAGS_data)));
  if (graded) {
    const FalseEdgeList list = readFalseEdges(falseEdgesPath(FLAGS_data));
    checkFalseEdges(list, graph, falseEdgesPath(FLAGS_data));
    for (const FalseEdge& e : list.edges) is_false_factor[e.factor] = true;
  }
  robust::OdometryChain chain;
  std::vector<robust::LoopClosure> closures;
  std::vector<bool> is_false;
  for (std::size_t f = 0; f < graph.factors.size(); ++f) {
    const Factor& factor = *graph.factors[f];
    if (robust::OdometryChain::isOdometry(factor)) {
      chain.add(factor);
    } else if (robust::isLoopClosure(factor)) {
      closures.push_back(robust::loopClosureOf(factor));
      is_false.push_back(is_false_factor[f]);
    }
  }
  std::cout << FLAGS_data << ": " << chain.links() << " odometry links, " << closures.size()
            << " loop closures\n";
  std::vector<bool> accepted;
  if (FLAGS_incremental) {
    std::vector<std::size_t> order(closures.size());
    for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return std::max(closures[a].from, closures[a].to) <
             std::max(closures[b].from, closures[b].to);
    });
    robust::IncrementalPairwiseConsistencyMaximization pcm(options);
    std::vector<double> step_seconds;
    std::size_t max_tests = 0, max_vertices = 0, searches = 0;
    bool exact = true;
    for (std::size_t c : order) {
      const Stopwatch t0;
      pcm.add(chain, closures[c]);
      step_seconds.push_back(t0.seconds());
      max_tests = std::max(max_tests, pcm.last().tests);
      max_vertices = std::max(max_vertices, pcm.last().vertices);
      searches += pcm.last().searched;
      exact = exact && pcm.last().exact;
    }
    accepted.assign(closures.size(), false);
    for (std::size_t k = 0; k < order.size(); ++k) accepted[order[k]] = pcm.accepted()[k];
    std::vector<double> sorted = step_seconds;
    std::sort(sorted.begin(), sorted.end());
    double total = 0;
    for (double s : step_seconds) total += s;
    const auto quantile = [&](double q) {
      return sorted.empty() ? 0.0
                            : sorted[std::min(sorted.size() - 1, std::size_t(q * sorted.size()))];
    };
    std::cout << "incremental: threshold " << options.threshold << ", window " << options.window
              << ", sample " << options.sample << "; " << total << " s in all, step p99 "
              << quantile(0.99) * 1e3 << " ms, max " << (sorted.empty() ? 0.0 : sorted.back() * 1e3)
              << " ms; at most " << max_tests << " tests and " << max_vertices
              << " vertices a step; " << searches << " clique searches, "
              << (exact ? "all exact" : "some NOT exact") << "; " << pcm.uncheckedPairs()
              << " pairs no odometry joins (untested, not in conflict)\n";
  } else {
    const robust::PcmResult r = robust::pairwiseConsistencyMaximization(chain, closures, options);
    accepted = r.accepted;
    std::cout << "batch: threshold " << r.threshold << ", "
              << closures.size() * (closures.size() - (closures.empty() ? 0 : 1)) / 2
              << " pairs tested in " << r.consistency_seconds << " s, " << r.consistent_pairs
              << " consistent, " << r.unchecked_pairs
              << " no odometry joins (untested, not in conflict: "
              << std::count(r.unchecked.begin(), r.unchecked.end(), true)
              << " closures in one); clique search " << r.clique_seconds << " s, "
              << (r.exact ? "exact (a maximum clique)"
                          : "NOT exact: the budget ran out, incremental PCM (threshold " +
                                std::to_string(options.threshold) + ") decided in " +
                                std::to_string(r.fallback_seconds) + " s")
              << "\n";
  }
  std::size_t n_accepted = 0, false_accepted = 0, true_rejected = 0, n_false = 0;
  for (std::size_t c = 0; c < closures.size(); ++c) {
    n_accepted += accepted[c];
    n_false += is_false[c];
    false_accepted += is_false[c] && accepted[c];
    true_rejected += !is_false[c] && !accepted[c];
  }
  std::cout << "accepted " << n_accepted << " of " << closures.size();
  if (graded)
    std::cout << "; false accepted " << false_accepted << " of " << n_false << ", true rejected "
              << true_rejected << " of " << closures.size() - n_false;
  std::cout << "\n";
  return 0;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_pcm", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::run(plugins, positional);
  });
}
