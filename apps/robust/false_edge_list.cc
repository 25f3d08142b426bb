// FalseEdgeList: see false_edge_list.h.
#include "apps/robust/false_edge_list.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/line_tokens.h"
#include "core/output_file.h"
#include "core/text_file.h"

namespace hamal::apps {

namespace {
const char kSpoiling[] = "# spoiling:";
const char kColumns[] = "factor from to group";
}  // namespace

std::string falseEdgesPath(const std::string& graph_path) { return graph_path + ".false"; }

void writeFalseEdges(const std::string& path, const FalseEdgeList& list) {
  for (const auto& [key, value] : list.spoiling)
    if (key.find_first_of(" \t=") != std::string::npos ||
        value.find_first_of(" \t\n") != std::string::npos)
      throw Error(path + ": spoiling entry '" + key + "=" + value + "' may not hold blanks");
  writeOutputFile(path, [&](std::ostream& out) {
    out << "# hamal_spoil: false loop closures of the graph file beside this one\n" << kSpoiling;
    for (const auto& [key, value] : list.spoiling) out << " " << key << "=" << value;
    out << "\n" << kColumns << "\n";
    for (const auto& e : list.edges)
      out << e.factor << " " << e.from << " " << e.to << " " << e.group << "\n";
  });
}

FalseEdgeList readFalseEdges(const std::string& path) {
  std::istringstream in(readTextFile(path, "the false-edge list (hamal_spoil writes it)"));
  FalseEdgeList list;
  std::string text;
  int line = 0;
  int spoiling_line = 0;
  bool columns = false;
  while (std::getline(in, text)) {
    ++line;
    if (text.rfind(kSpoiling, 0) == 0) {
      spoiling_line = line;
      std::istringstream fields(text.substr(sizeof(kSpoiling) - 1));
      std::string item;
      while (fields >> item) {
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
          LineTokens(path, line, {}).fail("spoiling entry '" + item + "' is not key=value");
        list.spoiling[item.substr(0, eq)] = item.substr(eq + 1);
      }
      continue;
    }
    if (text.empty() || text[0] == '#') continue;
    if (!columns) {
      if (text != kColumns)
        LineTokens(path, line, {}).fail(std::string("expected the column line '") + kColumns + "'");
      columns = true;
      continue;
    }
    // LineTokens reads fields after a tag: give the line a tag of its own.
    LineTokens tokens = LineTokens::split(path, line, "edge " + text);
    FalseEdge e;
    e.factor = tokens.id("factor");
    e.from = tokens.id("from");
    e.to = tokens.id("to");
    e.group = tokens.id("group");
    tokens.expectEnd();
    list.edges.push_back(e);
  }
  if (!columns) throw Error(path + ": no column line '" + std::string(kColumns) + "'");
  // The header states how many edges follow: a list cut at a line break
  // (or edited) would otherwise grade the run against the wrong truth.
  const auto outliers = list.spoiling.find("outliers");
  if (outliers != list.spoiling.end()) {
    const std::string& n = outliers->second;
    if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos || n.size() > 19)
      LineTokens(path, spoiling_line, {}).fail("outliers=" + n + " is not a count");
    if (std::stoull(n) != list.edges.size())
      LineTokens(path, spoiling_line, {})
          .fail("the header says outliers=" + n + " but the list has " +
                std::to_string(list.edges.size()) +
                " edges: a cut or edited list; spoil the graph again");
  }
  const auto factors = list.spoiling.find("graph_factors");
  if (factors != list.spoiling.end()) {
    const std::string& n = factors->second;
    if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos || n.size() > 19)
      LineTokens(path, spoiling_line, {}).fail("graph_factors=" + n + " is not a count");
  }
  return list;
}

void checkFalseEdges(const FalseEdgeList& list, const Graph& graph, const std::string& path) {
  // The graph's factor count, when the list records it, ties the pair: a
  // list beside another spoiling's graph is refused before any edge is read.
  const auto factors = list.spoiling.find("graph_factors");
  if (factors != list.spoiling.end() && factors->second != std::to_string(graph.factors.size()))
    throw Error(path + ": the list is of a graph of " + factors->second + " factors, " +
                graph.source + " has " + std::to_string(graph.factors.size()) +
                " (is this the list of that graph? spoil it again)");
  std::set<std::size_t> seen;
  for (const auto& e : list.edges) {
    const std::string which = path + ": false edge " + std::to_string(e.factor) + " (" +
                              std::to_string(e.from) + " -> " + std::to_string(e.to) + ")";
    if (e.factor >= graph.factors.size())
      throw Error(which + ": " + graph.source + " has only " +
                  std::to_string(graph.factors.size()) + " factors");
    if (!seen.insert(e.factor).second) throw Error(which + ": listed twice");
    const auto& keys = graph.factors[e.factor]->keys();
    if (keys.size() != 2 || keys[0] != X(e.from) || keys[1] != X(e.to))
      throw Error(which + ": factor " + std::to_string(e.factor) + " of " + graph.source +
                  " is not an edge between those poses (is this the list of that graph?)");
  }
}

}  // namespace hamal::apps
