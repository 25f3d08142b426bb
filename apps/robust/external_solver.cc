// The files a solver outside hamal exchanges with the robust benchmark: see
// external_solver.h.
#include "apps/robust/external_solver.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "core/line_tokens.h"
#include "core/output_file.h"
#include "core/text_file.h"
#include "factors/between_factor.h"

namespace hamal::apps {

namespace {
const char kColumns[] = "factor from to weight rejected";

std::string describe(const Factor& f, std::size_t index) {
  std::string s = "factor " + std::to_string(index) + " (" + f.tag();
  for (Key k : f.keys()) s += " " + k.str();
  return s + ")";
}
}  // namespace

std::vector<ExternalEdge> externalEdges(const Graph& graph) {
  if (!graph.fixed.empty())
    throw Error(graph.source + ": FIX lines (" + graph.fixed.begin()->str() +
                "...): a solver outside hamal gets measurements only; give a graph without "
                "fixed variables (the thesis protocol anchors pose 0 with its prior)");
  std::vector<ExternalEdge> edges;
  edges.reserve(graph.factors.size());
  for (std::size_t i = 0; i < graph.factors.size(); ++i) {
    const Factor& f = *graph.factors[i];
    const auto* between = dynamic_cast<const BetweenFactor*>(&f);
    const auto& keys = f.keys();
    if (!between || keys.size() != 2 || keys[0].kind() != kPoseKind || keys[1].kind() != kPoseKind)
      throw Error(graph.source + ": " + describe(f, i) +
                  ": a solver outside hamal takes relative-pose edges between two poses only "
                  "(EDGE_SE2, EDGE2)");
    if (f.lossFunction())
      throw Error(graph.source + ": " + describe(f, i) +
                  " carries a robust loss: the outside solver brings its own");
    ExternalEdge e;
    e.factor = i;
    e.from = keys[0].index();
    e.to = keys[1].index();
    e.measurement = between->measurement();
    e.information = between->information();
    e.loop_closure = robust::isLoopClosure(f);
    edges.push_back(e);
  }
  return edges;
}

void writeExternalDecisions(const std::string& path, const std::string& solver,
                            const std::string& graph_path,
                            const std::vector<ExternalDecision>& decisions) {
  writeOutputFile(path, [&](std::ostream& out) {
    out << "# " << solver << ": loop-closure decisions of " << graph_path << "\n"
        << kColumns << "\n"
        << std::setprecision(17);
    for (const auto& d : decisions) {
      out << d.factor << " " << d.from << " " << d.to << " ";
      if (std::isfinite(d.weight))
        out << d.weight;
      else
        out << "nan";
      out << " " << (d.rejected ? 1 : 0) << "\n";
    }
  });
}

ModelDecisions readExternalDecisions(const std::string& path, const Graph& graph) {
  std::istringstream in(readTextFile(path, "the decisions file (hamal_risam_native writes it)"));
  ModelDecisions out;
  out.rejected.assign(graph.factors.size(), -1);
  out.weight.assign(graph.factors.size(), std::numeric_limits<double>::quiet_NaN());
  std::string text;
  int line = 0;
  bool columns = false;
  while (std::getline(in, text)) {
    ++line;
    if (text.empty() || text[0] == '#') continue;
    if (!columns) {
      if (text != kColumns)
        LineTokens(path, line, {}).fail(std::string("expected the column line '") + kColumns + "'");
      columns = true;
      continue;
    }
    // LineTokens reads fields after a tag: give the line a tag of its own.
    LineTokens tokens = LineTokens::split(path, line, "decision " + text);
    const std::uint64_t factor = tokens.id("factor");
    const std::uint64_t from = tokens.id("from");
    const std::uint64_t to = tokens.id("to");
    const std::string weight = tokens.word("weight");
    const std::uint64_t rejected = tokens.id("rejected");
    tokens.expectEnd();
    if (factor >= graph.factors.size())
      tokens.fail("factor " + std::to_string(factor) + ": " + graph.source + " has only " +
                  std::to_string(graph.factors.size()) + " factors");
    const Factor& f = *graph.factors[factor];
    if (!robust::isLoopClosure(f))
      tokens.fail(describe(f, factor) + " of " + graph.source + " is not a loop closure");
    if (f.keys()[0] != X(from) || f.keys()[1] != X(to))
      tokens.fail(describe(f, factor) + " of " + graph.source + " is not an edge " +
                  std::to_string(from) + " -> " + std::to_string(to) +
                  " (are these the decisions of that graph?)");
    if (out.rejected[factor] != -1) tokens.fail("factor " + std::to_string(factor) + " twice");
    if (rejected > 1) tokens.fail("rejected must be 0 or 1, not " + std::to_string(rejected));
    out.rejected[factor] = static_cast<signed char>(rejected);
    if (weight != "nan")
      out.weight[factor] = LineTokens(path, line, {"weight", weight}).number("weight");
  }
  if (!columns) throw Error(path + ": no column line '" + std::string(kColumns) + "'");
  for (std::size_t i = 0; i < graph.factors.size(); ++i)
    if (out.rejected[i] == -1 && robust::isLoopClosure(*graph.factors[i]))
      throw Error(path + ": no decision on " + describe(*graph.factors[i], i) + " of " +
                  graph.source + " (a cut file?)");
  return out;
}

}  // namespace hamal::apps
