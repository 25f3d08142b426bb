// hamal_rpgo_native: Kimera-RPGO's RobustSolver (Rosinol et al., "Kimera",
// ICRA 2020; github.com/MIT-SPARK/Kimera-RPGO) with its Pairwise Consistency
// Maximization outlier rejection (Mangelson et al., "Pairwise Consistent
// Measurement Set Maximization", ICRA 2018), on GTSAM 4.2a8, driven under the
// thesis protocol (sec. 3.5.1; docs/PROTOCOL.md) on a graph spoiled by
// hamal_spoil, writing what hamal_robust --estimate grades
// (apps/robust/external_solver.h). README.md here says how to build it.
//
//   hamal_rpgo_native --data S.g2o --output rpgo.g2o --decisions rpgo.decisions --rows rows.csv
//
// The steps are hamal_risam_native's, the thesis protocol's: a prior on pose
// 0 with information diag(1e4, 1e4, 1e3), one step per pose with the edges
// that close at it, pose i guessed from RPGO's estimate of pose i-1 composed
// with the odometry; one RobustSolver::update per step. RPGO tells odometry
// from loop closures itself, by pose ids (from + 1 == to, the pose new in
// the update), as riSAM's harness does; its PCM measures every closure
// along the odometry chain, so a pose that odometry from the pose before it
// does not reach, or odometry against the id order, is refused naming it.
// PCM is Pcm2D with PcmParams' defaults (odometry check 10, pairwise check
// 5, Mahalanobis; flags), its non-incremental max clique, GNC off, LM: the
// library's defaults. RPGO re-solves the whole graph with LM after every
// update that brings a loop closure or the prior, and only then.
//
// A step's time is its update call and the calculateEstimate() the protocol
// reads next. The verdict on a loop closure is PCM's: kept (weight 1) when
// it is among the factors RPGO optimized last, else rejected (weight 0).
#include <gflags/gflags.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/slam/BetweenFactor.h>

#include <algorithm>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "KimeraRPGO/RobustSolver.h"
#include "KimeraRPGO/SolverParams.h"
#include "apps/common/cli.h"
#include "external_harness.h"
#include "protocol/thesis_protocol.h"

DEFINE_string(data, "", "the pose graph, e.g. one spoiled by hamal_spoil (g2o or TORO)");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_string(output, "",
              "write the final estimate here (g2o: its vertices, then the graph's factors)");
DEFINE_string(decisions, "",
              "write PCM's verdict on each loop closure here (factor from to weight rejected; "
              "apps/robust/external_solver.h)");
DEFINE_string(rows, "", "write per-step rows here (.csv or .jsonl), as hamal_robust --rows");
DEFINE_double(odom_threshold, KimeraRPGO::PcmParams().odom_threshold,
              "PCM's odometry check: largest Mahalanobis distance of a closure from odometry");
DEFINE_double(lc_threshold, KimeraRPGO::PcmParams().lc_threshold,
              "PCM's pairwise check: largest Mahalanobis distance between two closures' loops");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "Kimera-RPGO (PCM, GTSAM 4.2a8) under the thesis protocol on a spoiled pose graph;\n"
    "hamal_robust --estimate grades what it writes.\n\n"
    "  hamal_rpgo_native --data S.g2o --output rpgo.g2o --decisions rpgo.decisions --rows r.csv\n"
    "  hamal_robust --data S.g2o --estimate rpgo.g2o --decisions rpgo.decisions --summary s.json";

// What RPGO's PCM needs of the graph: every pose after the first reached by
// odometry from the pose before it, in id order (PCM composes closures with
// the odometry chain; a pose off it would be read as the identity).
void checkOdometryChain(const Graph& graph, const ThesisProtocol& protocol,
                        const std::vector<ExternalEdge>& edges) {
  for (const ExternalEdge& e : edges)
    if (!e.loop_closure && e.from + 1 != e.to)
      throw Error(graph.source + ": factor " + std::to_string(e.factor) + " (" +
                  std::to_string(e.from) + " -> " + std::to_string(e.to) +
                  "): odometry against the id order; Kimera-RPGO reads an edge as odometry only "
                  "from pose i to pose i + 1");
  std::unordered_map<std::uint64_t, bool> reached;
  for (const ExternalEdge& e : edges)
    if (!e.loop_closure) reached[e.to] = true;
  for (std::size_t i = 1; i < protocol.size(); ++i) {
    const std::uint64_t id = protocol.pose(i).index();
    if (!reached.count(id) || protocol.pose(i - 1).index() + 1 != id)
      throw Error(graph.source + ": pose " + std::to_string(id) +
                  " is not reached by odometry from the pose before it; Kimera-RPGO's PCM "
                  "measures loop closures along the odometry chain");
  }
}

HarnessOutcome run(const Graph& graph) {
  const std::vector<ExternalEdge> edges = externalEdges(graph);
  std::unordered_map<const Factor*, const ExternalEdge*> edge_of;
  for (std::size_t i = 0; i < edges.size(); ++i) edge_of[graph.factors[i].get()] = &edges[i];
  const ThesisProtocol protocol(graph);
  checkOdometryChain(graph, protocol, edges);

  KimeraRPGO::RobustSolverParams params;
  params.setPcm2DParams(FLAGS_odom_threshold, FLAGS_lc_threshold, KimeraRPGO::Verbosity::QUIET);
  KimeraRPGO::RobustSolver rpgo(params);
  std::vector<const ExternalEdge*> closures;
  HarnessOutcome out;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const Step step = protocol.step(i, out.estimate);
    gtsam::NonlinearFactorGraph factors;
    for (const FactorPtr& f : step.new_factors) {
      if (f == protocol.prior()) {
        factors.add(anchorOf(protocol, step));
        continue;
      }
      const ExternalEdge& e = *edge_of.at(f.get());
      factors.add(gtsam::BetweenFactor<gtsam::Pose2>(e.from, e.to, toGtsam(e.measurement),
                                                     noise(e.information)));
      if (e.loop_closure) closures.push_back(&e);
    }
    const gtsam::Values guesses = guessesOf(step);
    if (!timedStep(
            i, "rpgo", out, [&] { rpgo.update(factors, guesses); },
            [&] { return rpgo.calculateEstimate(); }))
      return out;
  }

  // PCM's inliers are the closures among the factors RPGO optimized last
  // (copies of the ones given: matched by poses and measurement).
  std::multimap<std::pair<gtsam::Key, gtsam::Key>, gtsam::Pose2> kept;
  for (const auto& f : rpgo.getFactorsUnsafe()) {
    const auto between = boost::dynamic_pointer_cast<gtsam::BetweenFactor<gtsam::Pose2>>(f);
    if (between)
      kept.emplace(std::make_pair(between->key1(), between->key2()), between->measured());
  }
  for (const ExternalEdge* e : closures) {
    auto [first, last] = kept.equal_range({e->from, e->to});
    auto match = std::find_if(
        first, last, [&](const auto& k) { return k.second.equals(toGtsam(e->measurement), 1e-9); });
    const bool rejected = match == last;
    if (!rejected) kept.erase(match);
    out.decisions.push_back({e->factor, e->from, e->to, rejected ? 0.0 : 1.0, rejected});
  }
  sortByFactor(out.decisions);
  return out;
}

int main(int argc, char** argv) {
  const auto positional = parseCommandLine(&argc, &argv, kUsage);
  return harnessMain(positional,
                     {FLAGS_data, FLAGS_format, FLAGS_output, FLAGS_decisions, FLAGS_rows},
                     "hamal_rpgo_native", "Kimera-RPGO", run);
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_rpgo_native", [&] { return hamal::apps::main(argc, argv); });
}
