// What a solver run outside hamal (plugins/risam: riSAM on GTSAM 4.2) is
// given and hands back, so that `hamal_robust --estimate` grades it exactly
// as it grades hamal's own robust models (apps/robust/README.md, "Solvers
// outside hamal"): the same spoiled file, the same clean optimum, the same
// false-edge list, the same ATE.
//
// Given: the spoiled graph as pose-graph edges (externalEdges), each marked
// odometry (a known inlier) or loop closure (a candidate), in the graph's
// factor order, which is the false-edge list's numbering; the solver steps
// through them with the thesis protocol (protocol/thesis_protocol.h).
//
// Handed back: the final estimate (a g2o file, writeG2o), the per-step rows
// (apps/bench/bench_writers.h: the report's times), and the solver's verdict
// on every loop closure:
//
//   # hamal_risam_native: loop-closure decisions of M3500-r1000.g2o
//   factor from to weight rejected
//   5453 12 3000 0.0123 1
//
// `factor` indexes the graph's factors as the false-edge list does, `from`
// and `to` are its pose ids, `weight` the solver's final weight of the
// closure ("nan" when it has none) and `rejected` 1 when the solver counts
// it as an outlier, else 0.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "apps/robust/robust_evaluation.h"
#include "core/graph.h"
#include "core/pose2.h"

namespace hamal::apps {

struct ExternalEdge {
  std::size_t factor = 0;  // index among the graph's factors
  std::uint64_t from = 0, to = 0;
  Pose2 measurement;  // pose `to` seen from pose `from`
  // As the file gives it: the information of g2o's and GTSAM's residual
  // (translation error in the measurement's frame).
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  bool loop_closure = false;  // robust::isLoopClosure: pose ids more than one apart
};

// Every factor of `graph`, in order. Throws hamal::Error naming graph.source
// and the factor (its index, tag and variables) for a factor that is not a
// between factor of two poses, or that carries a robust loss, and for a graph
// with FIX lines: an outside solver gets measurements only.
std::vector<ExternalEdge> externalEdges(const Graph& graph);

struct ExternalDecision {
  std::size_t factor = 0;
  std::uint64_t from = 0, to = 0;
  double weight = 0;  // NaN: the solver has none
  bool rejected = false;
};

// Writes the decisions file (header above), through OutputFile. `solver`
// and `graph_path` go into its comment line.
void writeExternalDecisions(const std::string& path, const std::string& solver,
                            const std::string& graph_path,
                            const std::vector<ExternalDecision>& decisions);

// Reads a decisions file and checks it against `graph`: every line names a
// loop closure of `graph` between the poses it says, once, and every loop
// closure has a line. The result is indexed by factor, as modelDecisions'
// (rejected -1 and weight NaN for the factors that are not loop closures).
// Throws hamal::Error("path:line: reason") or ("path: reason").
ModelDecisions readExternalDecisions(const std::string& path, const Graph& graph);

}  // namespace hamal::apps
