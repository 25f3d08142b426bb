// hamal_risam_native: riSAM (McGann, Rogers and Kaess, "Robust Incremental
// Smoothing and Mapping", ICRA 2023; github.com/rpl-cmu/risam) on GTSAM 4.2a8,
// driven under the thesis protocol (sec. 3.5.1; docs/PROTOCOL.md) on a graph
// spoiled by hamal_spoil, writing what hamal_robust --estimate grades
// (apps/robust/external_solver.h). README.md here says how to build it.
//
//   hamal_risam_native --data S.g2o --output risam.g2o --decisions risam.decisions --rows rows.csv
//
// The steps are the thesis protocol's (protocol/thesis_protocol.h, the
// same steps hamal's back-ends get): a prior on pose 0 with information
// diag(1e4, 1e4, 1e3), one step per pose with the edges that close at it,
// pose i guessed from riSAM's estimate of pose i-1 composed with the
// odometry. Odometry (pose ids one apart) and the prior are riSAM's known
// inliers, as in riSAM's experiments; every loop closure is a
// GenericGraduatedFactor<BetweenFactor<Pose2>> with riSAM's SIG kernel
// (shape 3), the candidate riSAM may switch off. riSAM's update takes one
// kind per call, so a step with both is two RISAM2::update calls, known
// inliers first; a pose whose only edges are loop closures enters with them.
// Parameters are the paper's (riSAM's experiments/exp_runner Factory.h,
// "risam"): Dogleg line search OUTWARD with deltas 1 (initial and least) to
// 50, converge_after_new_gnc, converge_mu, increment_outlier_mu, no
// converge_values; ISAM2Params are GTSAM's defaults.
//
// A step's time is its RISAM2::update calls and the calculateEstimate() the
// protocol reads next, as the GTSAM plugin's iSAM2 step (the rows' estimate
// phase is that call). The verdict on a loop closure is riSAM's own
// experiments' (ModeDetermination.h, chiSqInlierCheck): an inlier when its
// Mahalanobis distance at the final estimate is below the chi2 quantile of
// its dimension at 0.95 (7.81 for a 2D pose); its weight is the SIG kernel's
// at that distance and the closure's final mu.
#include <gflags/gflags.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/slam/BetweenFactor.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "apps/common/cli.h"
#include "external_harness.h"
#include "protocol/thesis_protocol.h"
#include "risam/GraduatedFactor.h"
#include "risam/GraduatedKernel.h"
#include "risam/RISAM2.h"

DEFINE_string(data, "", "the pose graph, e.g. one spoiled by hamal_spoil (g2o or TORO)");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_string(output, "",
              "write the final estimate here (g2o: its vertices, then the graph's factors)");
DEFINE_string(decisions, "",
              "write riSAM's verdict on each loop closure here (factor from to weight rejected; "
              "apps/robust/external_solver.h)");
DEFINE_string(rows, "", "write per-step rows here (.csv or .jsonl), as hamal_robust --rows");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "riSAM (GTSAM 4.2a8) under the thesis protocol on a spoiled pose graph; hamal_robust\n"
    "--estimate grades what it writes.\n\n"
    "  hamal_risam_native --data S.g2o --output risam.g2o --decisions risam.decisions --rows "
    "r.csv\n"
    "  hamal_robust --data S.g2o --estimate risam.g2o --decisions risam.decisions --summary s.json";

constexpr double kKernelShape = 3;  // the SIG kernel's c in riSAM's experiments

// riSAM with its convexification parameters readable: the weight of a
// closure is its kernel's at the closure's mu.
class ObservedRISAM2 : public risam::RISAM2 {
 public:
  using risam::RISAM2::RISAM2;
  double mu(std::size_t factor) const { return mu_.at(factor); }
};

risam::RISAM2::RISAM2Params papersParameters() {
  risam::DoglegLineSearchParams line_search;
  line_search.search_type = risam::DoglegLineSearchType::OUTWARD;
  line_search.init_delta = 1.0;
  line_search.min_delta = 1.0;
  line_search.max_delta = 50;
  risam::RISAM2::RISAM2Params params;
  params.converge_after_new_gnc = true;
  params.converge_mu = true;
  params.converge_values = false;
  params.increment_outlier_mu = true;
  params.optimization_params = line_search;
  return params;
}

HarnessOutcome run(const Graph& graph) {
  const std::vector<ExternalEdge> edges = externalEdges(graph);
  std::unordered_map<const Factor*, const ExternalEdge*> edge_of;
  for (std::size_t i = 0; i < edges.size(); ++i) edge_of[graph.factors[i].get()] = &edges[i];
  const ThesisProtocol protocol(graph);
  ObservedRISAM2 risam(papersParameters());
  std::vector<std::pair<const ExternalEdge*, std::size_t>> closures;  // edge, riSAM's index
  HarnessOutcome out;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const Step step = protocol.step(i, out.estimate);
    gtsam::NonlinearFactorGraph inliers, candidates;
    std::vector<const ExternalEdge*> candidate_edges;
    for (const FactorPtr& f : step.new_factors) {
      if (f == protocol.prior()) {
        inliers.add(anchorOf(protocol, step));
        continue;
      }
      const ExternalEdge& e = *edge_of.at(f.get());
      if (e.loop_closure) {
        candidates.add(risam::make_shared_graduated<gtsam::BetweenFactor<gtsam::Pose2>>(
            boost::make_shared<risam::SIGKernel>(kKernelShape), e.from, e.to,
            toGtsam(e.measurement), noise(e.information)));
        candidate_edges.push_back(&e);
      } else {
        inliers.add(gtsam::BetweenFactor<gtsam::Pose2>(e.from, e.to, toGtsam(e.measurement),
                                                       noise(e.information)));
      }
    }
    const gtsam::Values guesses = guessesOf(step);
    const auto update = [&] {
      if (!inliers.empty()) risam.update(inliers, guesses, true);
      if (!candidates.empty()) {
        const gtsam::ISAM2Result r =
            risam.update(candidates, inliers.empty() ? guesses : gtsam::Values(), false);
        for (std::size_t k = 0; k < candidate_edges.size(); ++k)
          closures.emplace_back(candidate_edges[k], r.newFactorsIndices.at(k));
      }
    };
    if (!timedStep(i, "risam", out, update, [&] { return risam.calculateEstimate(); })) return out;
  }

  const gtsam::Values final_estimate = risam.calculateEstimate();
  const double inlier_bound =
      boost::math::quantile(boost::math::chi_squared_distribution<double>(3), 0.95);
  for (const auto& [edge, index] : closures) {
    const auto& factor =
        dynamic_cast<const risam::GraduatedFactor&>(*risam.getFactorsUnsafe()[index]);
    const double distance = factor.residual(final_estimate);  // sqrt(2 error): Mahalanobis
    out.decisions.push_back({edge->factor, edge->from, edge->to,
                             factor.kernel()->weight(distance, risam.mu(index)),
                             !(distance < inlier_bound)});
  }
  sortByFactor(out.decisions);
  return out;
}

int main(int argc, char** argv) {
  const auto positional = parseCommandLine(&argc, &argv, kUsage);
  return harnessMain(positional,
                     {FLAGS_data, FLAGS_format, FLAGS_output, FLAGS_decisions, FLAGS_rows},
                     "hamal_risam_native", "riSAM", run);
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_risam_native", [&] { return hamal::apps::main(argc, argv); });
}
