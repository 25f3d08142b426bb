// FalseLoopClosures: spoils a pose graph with outlier loop closures the way
// the Vertigo datasets were made (Suenderhauf & Protzel, "Switchable
// constraints for robust pose graph SLAM", IROS 2012, and Vertigo's
// generateDataset.py), so that the robust loop-closure models around the
// thesis' back-ends (max-mixtures, FLAG's footing, ch. 4) can be measured
// against least squares and robust losses (apps/robust/README.md).
//
// A false loop closure is a between factor from pose i to pose j > i + 1
// (never odometry) whose measurement is a near-identity transform drawn as
// Vertigo draws it, dx, dy ~ N(0, 0.3 m), dtheta ~ N(0, 10 deg), with the
// information of the dataset's first loop closure. Poses are counted by
// their rank in id order (equal to the id in every public dataset). Policies:
//   random       i and j uniform over all poses
//   local        i uniform, j - i uniform in [2, local_window] (Vertigo: 20)
//   random-group, local-group: a unit is a group of group_size (Vertigo's
//                experiments: 10) consecutive edges (i+k, j+k) sharing one
//                measurement, the start drawn as above; the last group of N
//                is cut to what is left of N.
// Unlike Vertigo's script, no pose pair is used twice: a false edge never
// joins two poses that the clean graph or another false edge already joins,
// so the factor index says unambiguously which edge is false. A request for
// more false edges than the policy has free pose pairs is an error, and
// drawing gives up with an error, never loops, when the free pairs cannot
// hold the groups.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/graph.h"

namespace hamal::apps {

enum class SpoilPolicy { kRandom, kLocal, kRandomGroup, kLocalGroup };
// "random" | "local" | "random-group" | "local-group"; throws hamal::Error otherwise.
SpoilPolicy parseSpoilPolicy(const std::string& name);
const char* spoilPolicyName(SpoilPolicy policy);

struct SpoilOptions {
  std::size_t outliers = 0;  // N, false edges in all
  SpoilPolicy policy = SpoilPolicy::kRandom;
  std::uint64_t seed = 1;
  std::size_t group_size = 10;                                 // edges per group (group policies)
  std::size_t local_window = 20;                               // largest j - i (local policies)
  double sigma_xy = 0.3;                                       // metres, per translation axis
  double sigma_theta = 10.0 * 3.14159265358979323846 / 180.0;  // radians
};

// One false edge of a spoiled graph.
struct FalseEdge {
  std::size_t factor = 0;  // index in the spoiled graph's factors (file order)
  std::uint64_t from = 0;  // pose id i
  std::uint64_t to = 0;    // pose id j > i + 1
  std::size_t group = 0;   // which draw made it (one per edge without groups)
};

struct SpoiledGraph {
  Graph graph;  // the clean factors in their order, then the false ones
  std::vector<FalseEdge> false_edges;
};

// Free pose pairs the policy draws from in `clean` (pairs i < j with
// j - i >= 2, within the window for local policies, that no factor joins).
std::uint64_t freePosePairs(const Graph& clean, const SpoilOptions& options);

// Throws hamal::Error naming clean.source when: options are out of range
// (group_size or local_window too small), the graph has fewer than 3 poses
// or no loop closure between factor to take the information from, or
// options.outliers exceeds freePosePairs / cannot be placed.
SpoiledGraph spoilGraph(const Graph& clean, const SpoilOptions& options);

}  // namespace hamal::apps
