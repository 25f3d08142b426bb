// Batch Pairwise Consistency Maximization (pairwise_consistency_maximization.h).
#include "backends/robust/pairwise_consistency_maximization.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/incremental_pairwise_consistency_maximization.h"
#include "core/error.h"
#include "core/stopwatch.h"

namespace hamal::robust {

std::vector<OptionSpec> pcmOptionSpecs() {
  return {
      {"pcm_probability", "0.99",
       "PCM: the probability that a true loop closure passes every test PCM puts it to: half "
       "of the rest for the estimate's test, half for the pairwise tests (pcm_window + "
       "pcm_sample of them; batch PCM: one per other closure), each test's threshold the chi2 "
       "quantile of 3 dof at 1 - (1 - this) / (2 tests) (0.99 with the defaults: 12.84 and "
       "20.64)"},
      {"pcm_threshold", "auto",
       "PCM: that threshold given directly (> 0); auto: from pcm_probability"},
      {"pcm_clique_seconds", "0",
       "batch PCM: time budget of igraph's exact maximum-clique search; when it runs out, "
       "incremental PCM decides over the closures in order (not exact). 0: no budget, exact"},
      {"pcm_window", "20",
       "incremental PCM: K, the latest loop closures a new one is tested against and the "
       "maximum clique is recomputed over"},
      {"pcm_sample", "20",
       "incremental PCM: S, random draws among older closures; the accepted ones drawn are "
       "tested and join the clique"},
      {"pcm_seed", "1", "incremental PCM: seed of those draws"},
      {"pcm_covariance", "estimate",
       "estimate: a new loop closure is first tested against the back-end's estimate with its "
       "covariance (back-ends that give residualCovariance: aprilsam, aprilsam-top; the others "
       "and the first batch use the odometry) and rejected for good when it fails; odometry: "
       "the odometry chain's covariance only"},
  };
}

namespace {

void resolveThresholds(PcmOptions& p) {
  p.threshold = pcmThreshold(p, static_cast<std::size_t>(p.window + p.sample));
  p.estimate_threshold = pcmThreshold(p, 1);
}

}  // namespace

PcmOptions pcmOptionsFrom(const Options& options) {
  PcmOptions p;
  p.probability = options.getDouble("pcm_probability");
  if (!(p.probability > 0 && p.probability < 1))
    throw Error(options.owner() + ": pcm_probability must be in (0, 1)");
  const std::string& threshold = options.getString("pcm_threshold");
  p.threshold_given = threshold != "auto";
  if (p.threshold_given) {
    p.threshold = options.getDouble("pcm_threshold");
    if (!(p.threshold > 0) || !std::isfinite(p.threshold))
      throw Error(options.owner() + ": pcm_threshold must be positive (or auto)");
  }
  p.clique_seconds = options.getDouble("pcm_clique_seconds");
  if (!(p.clique_seconds >= 0) || !std::isfinite(p.clique_seconds))
    throw Error(options.owner() + ": pcm_clique_seconds must be >= 0");
  const long window = options.getInt("pcm_window");
  if (window < 1 || window > 100000)
    throw Error(options.owner() + ": pcm_window must be in [1, 100000]");
  const long sample = options.getInt("pcm_sample");
  if (sample < 0 || sample > 100000)
    throw Error(options.owner() + ": pcm_sample must be in [0, 100000]");
  const long seed = options.getInt("pcm_seed");
  if (seed < 0) throw Error(options.owner() + ": pcm_seed must be >= 0");
  p.window = static_cast<int>(window);
  p.sample = static_cast<int>(sample);
  p.seed = static_cast<std::uint64_t>(seed);
  resolveThresholds(p);
  const std::string& covariance = options.getString("pcm_covariance");
  if (covariance == "estimate")
    p.covariance = PcmOptions::Covariance::kEstimate;
  else if (covariance == "odometry")
    p.covariance = PcmOptions::Covariance::kOdometry;
  else
    throw Error(options.owner() + ": pcm_covariance must be estimate or odometry, not '" +
                covariance + "'");
  return p;
}

PcmOptions defaultPcmOptions() {
  PcmOptions p;
  resolveThresholds(p);
  return p;
}

double pcmThreshold(const PcmOptions& options, std::size_t tests) {
  if (options.threshold_given) return options.threshold;
  const double n = static_cast<double>(std::max<std::size_t>(tests, 1));
  return chiSquareQuantile(3, 1 - (1 - options.probability) / (2 * n));
}

ConsistencyGraph consistencyGraph(const OdometryChain& chain,
                                  const std::vector<LoopClosure>& closures, double threshold,
                                  std::size_t* unchecked_pairs, std::vector<bool>* unchecked) {
  if (!(threshold > 0)) throw Error("pairwise consistency: threshold must be positive");
  ConsistencyGraph g;
  g.vertices = static_cast<int>(closures.size());
  if (unchecked_pairs) *unchecked_pairs = 0;
  if (unchecked) unchecked->assign(closures.size(), false);
  for (std::size_t a = 0; a < closures.size(); ++a)
    for (std::size_t b = a + 1; b < closures.size(); ++b) {
      const std::optional<CycleError> cycle = cycleThroughOdometry(chain, closures[a], closures[b]);
      if (!cycle) {
        if (unchecked_pairs) ++*unchecked_pairs;
        if (unchecked) (*unchecked)[a] = (*unchecked)[b] = true;
      }
      if (!cycle || cycle->mahalanobis2 < threshold)
        g.edges.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
  return g;
}

PcmResult pairwiseConsistencyMaximization(const OdometryChain& chain,
                                          const std::vector<LoopClosure>& closures,
                                          const PcmOptions& options,
                                          const std::vector<bool>& preferred) {
  PcmResult r;
  r.accepted.assign(closures.size(), false);
  const Stopwatch t0;
  // Each closure is tested against every other here: at least as many
  // tests as incremental PCM's, so at least its threshold.
  if (!(options.threshold > 0)) throw Error("pairwise consistency: threshold must be positive");
  r.threshold = std::max(options.threshold,
                         pcmThreshold(options, closures.empty() ? 1 : closures.size() - 1));
  const ConsistencyGraph g =
      consistencyGraph(chain, closures, r.threshold, &r.unchecked_pairs, &r.unchecked);
  r.consistency_seconds = t0.seconds();
  r.consistent_pairs = g.edges.size() - r.unchecked_pairs;
  const CliqueResult clique = maximumClique(g, preferred, options.clique_seconds);
  r.clique_seconds = clique.seconds;
  r.exact = clique.exact;
  for (int v : clique.members) r.accepted[static_cast<std::size_t>(v)] = true;
  if (!clique.exact) {
    // The budget ran out: incremental PCM's bounded cliques decide.
    const Stopwatch t1;
    IncrementalPairwiseConsistencyMaximization incremental(options);
    for (const LoopClosure& c : closures) incremental.add(chain, c);
    r.accepted = incremental.accepted();
    r.fallback_seconds = t1.seconds();
  }
  return r;
}

}  // namespace hamal::robust
