// FalseEdgeList: the file hamal_spoil writes beside a spoiled graph, saying
// which of its edges are false (apps/robust/README.md), so the evaluation
// knows the truth without a second copy of the dataset: the clean graph is
// the spoiled one minus these edges.
//
//   # hamal_spoil: false loop closures of the graph file beside this one
//   # spoiling: source=M3500.toro policy=random outliers=100 seed=1 group_size=10 local_window=20
//   factor from to group
//   5453 12 3000 0
//
// `factor` is the edge's index among the graph file's factor lines (vertex
// and FIX lines not counted), `from` and `to` its pose ids, `group` the draw
// that made it. The path is the graph's path + ".false". hamal_spoil's header
// also says outliers=N, the number of edge lines, and graph_factors=M, the
// factor count of the graph beside it; a reader refuses a list whose lines
// disagree with either (a cut file, a list beside another graph).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "apps/robust/false_loop_closures.h"
#include "core/graph.h"

namespace hamal::apps {

struct FalseEdgeList {
  std::map<std::string, std::string> spoiling;  // the "# spoiling:" key=value pairs
  std::vector<FalseEdge> edges;
};

std::string falseEdgesPath(const std::string& graph_path);

// Written through OutputFile, as writeG2o is.
void writeFalseEdges(const std::string& path, const FalseEdgeList& list);
// Throws hamal::Error("path:line: reason") for a malformed file, and for one
// whose edge lines are not the outliers=N of its header.
FalseEdgeList readFalseEdges(const std::string& path);
// Throws hamal::Error naming `path` unless every listed edge is, in `graph`,
// a factor on exactly the poses (from, to), no factor is listed twice, and
// `graph` has the header's graph_factors=M factors (when it says).
void checkFalseEdges(const FalseEdgeList& list, const Graph& graph, const std::string& path);

}  // namespace hamal::apps
