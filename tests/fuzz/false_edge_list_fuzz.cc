// libFuzzer target: the false-edge list reader of the robust benchmark
// (apps/robust/false_edge_list.h) on arbitrary bytes, as the list beside a
// spoiled graph. Reading fails with a hamal::Error whose message names the
// file and fits a terminal, or gives a list that agrees with its header
// (as many edges as its outliers=N says), which writeFalseEdges writes and
// readFalseEdges reads back to the same list. Any other exception, a crash
// or a sanitizer report is a bug.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "apps/robust/false_edge_list.h"
#include "core/error.h"

namespace {

namespace fs = std::filesystem;

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "false_edge_list_fuzz: %s\n", what.c_str());
  std::abort();
}

const std::string& folder() {
  static const std::string* dir = [] {
    std::string d = (fs::temp_directory_path() / "hamal_false_edges_fuzz_XXXXXX").string();
    if (!::mkdtemp(d.data())) bug("cannot make a scratch folder");
    return new std::string(d);
  }();
  return *dir;
}

void checkMessage(const std::string& message, const std::string& file) {
  for (unsigned char c : message)
    if (c < 0x20 || c >= 0x7f) bug("an error message holds a raw control byte: " + message);
  if (message.size() > 4000)
    bug("an error message of " + std::to_string(message.size()) + " bytes");
  if (message.rfind(file, 0) != 0) bug("an error message that does not name the file: " + message);
}

bool same(const hamal::apps::FalseEdgeList& a, const hamal::apps::FalseEdgeList& b) {
  if (a.spoiling != b.spoiling || a.edges.size() != b.edges.size()) return false;
  for (std::size_t i = 0; i < a.edges.size(); ++i)
    if (a.edges[i].factor != b.edges[i].factor || a.edges[i].from != b.edges[i].from ||
        a.edges[i].to != b.edges[i].to || a.edges[i].group != b.edges[i].group)
      return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = folder() + "/spoiled.g2o.false";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  hamal::apps::FalseEdgeList list;
  try {
    list = hamal::apps::readFalseEdges(path);
  } catch (const hamal::Error& e) {
    checkMessage(e.what(), path);
    return 0;
  } catch (const std::exception& e) {
    bug(std::string("the reader threw something other than hamal::Error: ") + e.what());
  }
  const auto outliers = list.spoiling.find("outliers");
  if (outliers != list.spoiling.end() && std::stoull(outliers->second) != list.edges.size())
    bug("a list of " + std::to_string(list.edges.size()) +
        " edges read with outliers=" + outliers->second);
  const std::string again = folder() + "/again.g2o.false";
  try {
    hamal::apps::writeFalseEdges(again, list);
    if (!same(hamal::apps::readFalseEdges(again), list)) bug("a list read back differs");
  } catch (const hamal::Error& e) {
    bug(std::string("a list read does not write and read back: ") + e.what());
  }
  return 0;
}
