// ConsistentGroup: see consistent_group.h.
#include "backends/robust/consistent_group.h"

#include "backends/robust/loop_closure_consistency.h"
#include "backends/robust/odometry_chain.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "core/error.h"

namespace hamal::robust {

std::vector<bool> consistentGroup(const std::vector<FactorPtr>& inliers,
                                  const std::vector<const Factor*>& candidates,
                                  double clique_seconds) {
  OdometryChain odometry;
  for (const FactorPtr& f : inliers)
    if (OdometryChain::isOdometry(*f)) odometry.add(*f);
  std::vector<LoopClosure> closures;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    try {
      closures.push_back(loopClosureOf(*candidates[i]));
      index.push_back(i);
    } catch (const Error&) {
      // not a relative pose: no test can place it in the group
    }
  }
  if (closures.size() < 2) return {};
  PcmOptions options = defaultPcmOptions();
  options.clique_seconds = clique_seconds;
  const PcmResult pcm = pairwiseConsistencyMaximization(odometry, closures, options);
  std::vector<bool> group(candidates.size(), false);
  for (std::size_t k = 0; k < closures.size(); ++k) group[index[k]] = pcm.accepted[k];
  return group;
}

}  // namespace hamal::robust
