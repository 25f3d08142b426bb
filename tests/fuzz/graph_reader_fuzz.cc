// libFuzzer target: the graph reader (core/graph_io.h) on arbitrary bytes
// (tests/fuzz/README.md). The first byte picks the format
// ('g' g2o, 't' TORO, 's' GTSAM-style, anything else: detected); the rest is
// the file. Whatever the bytes, reading either fails with a hamal::Error
// whose message fits a terminal, or gives a graph that, written as g2o and
// read back, has the same factors and values: writing that graph again gives
// the same text. Any other exception, a crash or a sanitizer report is a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/graph_io.h"

namespace {

const hamal::Registry& registry() {
  static const hamal::Registry* r = [] {
    auto* reg = new hamal::Registry;
    hamal::registerBuiltins(*reg);
    return reg;
  }();
  return *r;
}

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "graph_reader_fuzz: %s\n", what.c_str());
  std::abort();
}

void checkMessage(const std::string& message) {
  for (unsigned char c : message)
    if (c < 0x20 || c >= 0x7f) bug("an error message holds a raw control byte: " + message);
  if (message.size() > 4000)
    bug("an error message of " + std::to_string(message.size()) + " bytes");
}

std::string g2oText(const hamal::Graph& graph) {
  std::ostringstream os;
  hamal::writeG2o(os, graph.initial, graph.factors);
  return os.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  hamal::Format format = hamal::Format::kAuto;
  std::string name = "fuzz";
  switch (data[0]) {
    case 'g':
      format = hamal::Format::kG2o;
      name = "fuzz.g2o";
      break;
    case 't':
      format = hamal::Format::kToro;
      name = "fuzz.toro";
      break;
    case 's':
      format = hamal::Format::kGtsam;
      name = "fuzz.txt";
      break;
    default:
      break;
  }
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);

  hamal::Graph graph;
  try {
    std::istringstream in(text);
    graph = hamal::readGraph(in, name, registry(), format);
  } catch (const hamal::Error& e) {
    checkMessage(e.what());
    return 0;
  } catch (const std::exception& e) {
    bug(std::string("the reader threw something other than hamal::Error: ") + e.what());
  }

  std::string first;
  try {
    first = g2oText(graph);
  } catch (const hamal::Error& e) {
    // A graph g2o cannot hold (a pose and a landmark sharing an id in a
    // GTSAM-style file): refused before writing, with a message.
    checkMessage(e.what());
    return 0;
  }
  hamal::Graph again;
  try {
    std::istringstream in(first);
    again = hamal::readGraph(in, "written.g2o", registry(), hamal::Format::kG2o);
  } catch (const hamal::Error& e) {
    bug(std::string("the written g2o does not read back: ") + e.what() + "\n" + first);
  }
  if (again.factors.size() != graph.factors.size()) bug("the factor count changed");
  if (again.initial.size() != graph.initial.size()) bug("the variable count changed");
  for (std::size_t i = 0; i < graph.factors.size(); ++i) {
    if (again.factors[i]->tag() != graph.factors[i]->tag()) bug("a factor's tag changed");
    if (again.factors[i]->keys() != graph.factors[i]->keys()) bug("a factor's keys changed");
  }
  if (g2oText(again) != first) bug("writing the graph read back gives other text:\n" + first);
  return 0;
}
