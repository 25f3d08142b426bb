// Reading and writing graph files: see graph_io.h. The factor graph of
// thesis sec. 2.2 as the public datasets store it (g2o, TORO, GTSAM-style);
// the information conventions of each format are in graph_io.h and
// third_party_notes/datasets.md.
//
// The reader is strict on purpose: a dataset that is read "mostly" gives
// benchmark figures nobody can reproduce, so every line is either understood
// completely or the whole read fails with "file:line: reason".
#include "core/graph_io.h"

#include <unistd.h>

#include <Eigen/LU>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <istream>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/information.h"
#include "core/line_tokens.h"
#include "core/output_file.h"
#include "core/relative_pose_measurement.h"
#include "core/text_file.h"

namespace hamal {

namespace {
constexpr EnumNames<Format, 4> kFormats = {{{Format::kAuto, "auto"},
                                            {Format::kG2o, "g2o"},
                                            {Format::kToro, "toro"},
                                            {Format::kGtsam, "gtsam"}}};
}  // namespace

Format parseFormat(const std::string& name) { return parseEnum(kFormats, name, "file format"); }

const char* formatName(Format format) { return enumName(kFormats, format); }

namespace {

constexpr const char* kVertexSe2 = "VERTEX_SE2";
constexpr const char* kVertexXy = "VERTEX_XY";
constexpr const char* kVertex2 = "VERTEX2";
constexpr const char* kFix = "FIX";

// The tags this file reads itself, per format. GTSAM's loader also accepts
// g2o's vertex lines, so GTSAM-style files may carry them.
std::vector<std::string> ownTags(Format format) {
  switch (format) {
    case Format::kG2o:
      return {kVertexSe2, kVertexXy, kFix};
    case Format::kToro:
      return {kVertex2};
    case Format::kGtsam:
      return {kVertex2, kVertexSe2, kVertexXy};
    case Format::kAuto:
      break;
  }
  return {};
}

bool isOwnTag(Format format, const std::string& tag) {
  const auto tags = ownTags(format);
  return std::find(tags.begin(), tags.end(), tag) != tags.end();
}

std::string knownTags(Format format, const Registry& registry) {
  std::set<std::string> tags;
  for (const auto& t : ownTags(format)) tags.insert(t);
  for (const FactorInfo* info : registry.factors())
    if (info->format == formatName(format)) tags.insert(info->tag);
  std::string out;
  for (const auto& t : tags) out += (out.empty() ? "" : ", ") + t;
  return out.empty() ? "(none registered)" : out;
}

std::string kindName(char kind) {
  if (kind == kPoseKind) return "pose";
  if (kind == kLandmarkKind) return "landmark";
  return std::string("variable of kind '") + kind + "'";
}

std::string describe(Key key) { return kindName(key.kind()) + " " + std::to_string(key.index()); }

// A data line: its number and its fields (blank lines and '#' comments are
// not data lines).
struct Line {
  int number;
  std::string text;
};

std::vector<Line> dataLines(const std::string& text) {
  std::vector<Line> lines;
  std::size_t begin = 0;
  int number = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    ++number;
    const std::size_t first = text.find_first_not_of(" \t\r\f\v", begin);
    if (first < end && text[first] != '#')
      lines.push_back({number, text.substr(begin, end - begin)});
    begin = end + 1;
  }
  return lines;
}

std::string firstWord(const std::string& text) {
  std::istringstream is(text);
  std::string word;
  is >> word;
  return word;
}

std::string lowerExtension(const std::string& name) {
  std::string ext = std::filesystem::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// Format::kAuto resolved, with the reason (for messages about unknown tags).
struct Detected {
  Format format;
  std::string reason;
};

Detected detectFormat(const std::string& name, const std::vector<Line>& lines,
                      const Registry& registry) {
  const std::string ext = lowerExtension(name);
  if (ext == ".g2o") return {Format::kG2o, "from the .g2o file name"};
  if (ext == ".toro") return {Format::kToro, "from the .toro file name"};

  // Tags that only g2o uses: its vertex lines, FIX, and every tag registered
  // for g2o alone (a plugin's g2o edge counts too).
  std::set<std::string> g2o_tags = {kVertexSe2, kVertexXy, kFix};
  std::set<std::string> other_tags = {kVertex2, "EDGE2", "ODOMETRY", "LANDMARK"};
  for (const FactorInfo* info : registry.factors())
    if (info->format != "g2o") other_tags.insert(info->tag);
  for (const FactorInfo* info : registry.factors())
    if (info->format == "g2o" && !other_tags.count(info->tag)) g2o_tags.insert(info->tag);

  // EDGE2 decides over g2o's tags: GTSAM-style files may carry g2o's vertex
  // lines, and then their EDGE2 matrices are still TORO's or GTSAM's.
  const Line* gtsam_line = nullptr;
  const Line* g2o_line = nullptr;
  const Line* edge2_line = nullptr;
  const Line* vertex2_line = nullptr;
  std::string g2o_tag, gtsam_tag;
  for (const Line& line : lines) {
    const std::string tag = firstWord(line.text);
    if (tag == "ODOMETRY" || tag == "LANDMARK") {
      gtsam_line = &line;
      gtsam_tag = tag;
      break;
    }
    if (!g2o_line && (g2o_tags.count(tag) || tag.rfind("EDGE_SE2", 0) == 0)) {
      g2o_line = &line;
      g2o_tag = tag;
    }
    if (!edge2_line && tag == "EDGE2") edge2_line = &line;
    if (!vertex2_line && tag == kVertex2) vertex2_line = &line;
  }
  if (gtsam_line)
    return {Format::kGtsam,
            "from its " + gtsam_tag + " line " + std::to_string(gtsam_line->number)};
  const Line* ambiguous = edge2_line ? edge2_line : g2o_line ? nullptr : vertex2_line;
  if (ambiguous)
    throw Error(name + ":" + std::to_string(ambiguous->number) + ": " + firstWord(ambiguous->text) +
                " lines are ambiguous: TORO files (like M3500.toro) give each EDGE2 an "
                "INFORMATION matrix in the order I11 I12 I22 I33 I13 I23, GTSAM-style files "
                "(like w20000.txt) give a COVARIANCE matrix in the order c11 c12 c13 c22 c23 "
                "c33, and the file name does not say which; pass --format=toro or "
                "--format=gtsam");
  if (g2o_line)
    return {Format::kG2o, "from its " + g2o_tag + " line " + std::to_string(g2o_line->number)};
  const Line& first = lines.front();
  throw Error(name + ":" + std::to_string(first.number) + ": cannot tell the file's format from " +
              "its name or its tags (first tag " + quoted(firstWord(first.text)) +
              "); pass --format=g2o, --format=toro or --format=gtsam. Known tags: g2o: " +
              knownTags(Format::kG2o, registry) + "; toro: " + knownTags(Format::kToro, registry) +
              "; gtsam: " + knownTags(Format::kGtsam, registry));
}

struct Vertex {
  Key key;
  std::string tag;
  int line;
};

// Reads the fields of a vertex line into `graph`; g2o has one id space for
// poses and landmarks, so there an id may be defined once whatever its kind.
void readVertex(LineTokens& tokens, Format format, Graph& graph, std::map<Key, Vertex>& vertices,
                std::map<std::uint64_t, Key>& by_index) {
  const std::string tag = tokens.tag();
  const std::uint64_t id = tokens.id("id");
  if (id > Key::kMaxIndex)
    tokens.fail("id " + std::to_string(id) + " is too large (at most " +
                std::to_string(Key::kMaxIndex) + ")");
  const bool point = tag == kVertexXy;
  const Key key = point ? L(id) : X(id);
  const double x = tokens.number("x");
  const double y = tokens.number("y");
  const double theta = point ? 0.0 : tokens.angle("theta");
  tokens.expectEnd();

  auto same = vertices.find(key);
  if (same != vertices.end())
    tokens.fail("duplicate vertex id " + std::to_string(id) + ": line " +
                std::to_string(same->second.line) + " already defines it (" + same->second.tag +
                ")");
  auto other = by_index.find(id);
  if (format == Format::kG2o && other != by_index.end()) {
    const Vertex& v = vertices.at(other->second);
    tokens.fail("duplicate vertex id " + std::to_string(id) + ": line " + std::to_string(v.line) +
                " already defines it as a " + v.tag +
                " (g2o has one id space for poses and landmarks)");
  }
  if (point)
    graph.initial.insert(key, Point2(x, y));
  else
    graph.initial.insert(key, Pose2(x, y, theta));
  vertices.emplace(key, Vertex{key, tag, tokens.line()});
  by_index.emplace(id, key);
}

FactorPtr readFactor(LineTokens& tokens, const FactorInfo& info) {
  FactorPtr factor;
  const std::string where = tokens.where();
  try {
    factor = info.parse(tokens);
    if (!factor) tokens.fail(tokens.tag() + ": the factor kind's parse function returned nothing");
    // Catches a parse function (a plugin's, say) that ignores trailing fields.
    tokens.expectEnd();
    const std::vector<Key>& keys = factor->keys();
    for (std::size_t a = 0; a < keys.size(); ++a)
      for (std::size_t b = a + 1; b < keys.size(); ++b)
        if (keys[a] == keys[b])
          tokens.fail(tokens.tag() + " names " + describe(keys[a]) +
                      " twice: a factor's variables must be distinct");
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(where + ":", 0) == 0) throw;
    throw Error(where + ": " + what);
  } catch (const std::exception& e) {
    throw Error(where + ": " + tokens.tag() + ": " + e.what());
  }
  return factor;
}

// When the file lists vertices, each variable an edge names must be one of
// them (of the same kind, and of the dimension the factor expects).
void checkFactorKeys(const std::string& name, const Graph& graph, const std::vector<int>& lines,
                     const std::map<Key, Vertex>& vertices,
                     const std::map<std::uint64_t, Key>& by_index) {
  for (std::size_t i = 0; i < graph.factors.size(); ++i) {
    const Factor& f = *graph.factors[i];
    const std::string where = name + ":" + std::to_string(lines[i]) + ": " + f.tag() + " ";
    const auto& sizes = f.costFunction()->parameter_block_sizes();
    for (std::size_t j = 0; j < f.keys().size(); ++j) {
      const Key k = f.keys()[j];
      auto v = vertices.find(k);
      if (v == vertices.end()) {
        auto other = by_index.find(k.index());
        if (other != by_index.end()) {
          const Vertex& o = vertices.at(other->second);
          throw Error(where + "refers to " + describe(k) + " but " + std::to_string(k.index()) +
                      " is a " + o.tag + " (line " + std::to_string(o.line) + ")");
        }
        throw Error(where + "refers to " + describe(k) +
                    ", which no VERTEX line defines (the file lists vertices, so every "
                    "variable needs one)");
      }
      if (sizes[j] != graph.initial.dim(k))
        throw Error(where + "expects " + std::to_string(sizes[j]) + " parameters for " +
                    describe(k) + " but its " + v->second.tag + " (line " +
                    std::to_string(v->second.line) + ") has " +
                    std::to_string(graph.initial.dim(k)));
    }
  }
}

// Without vertices the edges define the variables; in g2o one id still names
// one variable, so an id used as a pose and as a landmark is an error.
void checkOneIdSpace(const std::string& name, const Graph& graph, const std::vector<int>& lines) {
  std::map<std::uint64_t, std::pair<Key, int>> seen;
  for (std::size_t i = 0; i < graph.factors.size(); ++i)
    for (Key k : graph.factors[i]->keys()) {
      auto [it, inserted] = seen.emplace(k.index(), std::make_pair(k, lines[i]));
      if (!inserted && it->second.first != k)
        throw Error(name + ":" + std::to_string(lines[i]) + ": " + graph.factors[i]->tag() +
                    " refers to " + describe(k) + " but line " + std::to_string(it->second.second) +
                    " uses " + std::to_string(k.index()) + " as a " +
                    kindName(it->second.first.kind()) +
                    " (g2o has one id space for poses and landmarks)");
    }
}

Graph readText(const std::string& text, const std::string& name, const Registry& registry,
               Format format) {
  const std::vector<Line> lines = dataLines(text);
  if (lines.empty()) throw Error(name + ": empty file: no vertex and no factor");
  std::string reason = "as requested";
  if (format == Format::kAuto) {
    Detected d = detectFormat(name, lines, registry);
    format = d.format;
    reason = d.reason;
  }
  const std::string format_name = formatName(format);

  Graph graph;
  graph.source = name;
  std::map<Key, Vertex> vertices;
  std::map<std::uint64_t, Key> by_index;  // the first vertex of each id
  std::vector<int> factor_lines;
  std::vector<std::pair<std::uint64_t, int>> fixes;  // id, line
  for (const Line& line : lines) {
    LineTokens tokens = LineTokens::split(name, line.number, line.text);
    tokens.setRegistry(&registry, format_name);
    const std::string& tag = tokens.tag();
    if (isOwnTag(format, tag)) {
      if (tag == kFix) {
        if (tokens.remaining() == 0) tokens.fail("FIX line names no vertex id");
        while (tokens.remaining() > 0) fixes.emplace_back(tokens.id("id"), line.number);
      } else {
        readVertex(tokens, format, graph, vertices, by_index);
      }
      continue;
    }
    const FactorInfo* info = registry.findFactor(format_name, tag);
    if (!info)
      tokens.fail("unknown tag " + quoted(tag) + " for format " + format_name + " (" + reason +
                  "); known tags: " + knownTags(format, registry));
    graph.add(readFactor(tokens, *info));
    factor_lines.push_back(line.number);
  }

  if (vertices.empty() && graph.factors.empty())
    throw Error(name + ": empty file: no vertex and no factor");
  if (!vertices.empty())
    checkFactorKeys(name, graph, factor_lines, vertices, by_index);
  else if (format == Format::kG2o)
    checkOneIdSpace(name, graph, factor_lines);

  for (const auto& [id, line] : fixes) {
    const std::string where = name + ":" + std::to_string(line) + ": ";
    auto v = by_index.find(id);
    if (v != by_index.end()) {
      graph.fixed.insert(v->second);
      continue;
    }
    if (!vertices.empty())
      throw Error(where + "FIX refers to id " + std::to_string(id) + ", which no vertex defines");
    bool found = false;
    for (const auto& f : graph.factors)
      for (Key k : f->keys())
        if (!found && k.index() == id) {
          graph.fixed.insert(k);
          found = true;
        }
    if (!found)
      throw Error(where + "FIX refers to id " + std::to_string(id) +
                  ", which no vertex or edge names");
  }
  return graph;
}

}  // namespace

Graph readGraph(std::istream& in, const std::string& name, const Registry& registry,
                Format format) {
  return readText(readTextStream(in, name), name, registry, format);
}

Graph readGraph(const std::string& path, const Registry& registry, Format format) {
  return readText(readTextFile(path), path, registry, format);
}

namespace {

// Everything that would make the written file unreadable, or read back as
// another graph, is refused before a byte is written.
void checkWritable(const Values& values, const std::vector<FactorPtr>& factors,
                   const std::set<Key>& fixed) {
  std::map<std::uint64_t, Key> by_index;
  auto claim = [&](Key k) {
    auto [it, inserted] = by_index.emplace(k.index(), k);
    if (!inserted && it->second != k)
      throw Error("cannot write g2o: " + it->second.str() + " and " + k.str() + " share id " +
                  std::to_string(k.index()) + ", and g2o has one id space for poses and landmarks");
  };
  for (Key k : values.keys()) {
    const VariableType type = values.type(k);
    const bool ok = (k.kind() == kPoseKind && type == VariableType::kPose2) ||
                    (k.kind() == kLandmarkKind && type == VariableType::kPoint2);
    if (!ok)
      throw Error("cannot write g2o: variable " + k.str() + " is a " + typeName(type) +
                  "; g2o vertices are poses x<id> (VERTEX_SE2) and landmarks l<id> (VERTEX_XY)");
    claim(k);
  }
  for (const auto& f : factors) {
    if (!f) throw Error("cannot write g2o: null factor");
    for (Key k : f->keys()) {
      claim(k);
      if (!values.empty() && !values.contains(k))
        throw Error("cannot write g2o: a " + f->tag() + " factor refers to " + k.str() +
                    ", which has no value; a g2o file lists a vertex for every variable or "
                    "for none");
    }
  }
  // FIX names an id: it must be one the file defines, as the reader checks.
  for (Key k : fixed) {
    bool named = values.contains(k);
    for (std::size_t i = 0; !named && i < factors.size(); ++i)
      for (Key fk : factors[i]->keys()) named |= fk == k;
    if (!named)
      throw Error("cannot write g2o: fixed variable " + k.str() +
                  " has no vertex and no factor, so its FIX line would name an unknown id");
  }
}

}  // namespace

void writeG2o(std::ostream& out, const Values& values, const std::vector<FactorPtr>& factors,
              const std::set<Key>& fixed) {
  checkWritable(values, factors, fixed);
  const std::streamsize old_precision = out.precision(17);
  const std::ios_base::fmtflags old_flags = out.flags();
  out.unsetf(std::ios_base::floatfield);
  for (Key k : values.keys()) {
    const Values::Entry& e = values.entry(k);
    if (e.type == VariableType::kPose2)
      out << kVertexSe2 << ' ' << k.index() << ' ' << e.data[0] << ' ' << e.data[1] << ' '
          << e.data[2] << '\n';
    else
      out << kVertexXy << ' ' << k.index() << ' ' << e.data[0] << ' ' << e.data[1] << '\n';
  }
  if (!fixed.empty()) {
    out << kFix;
    for (Key k : fixed) out << ' ' << k.index();
    out << '\n';
  }
  for (const auto& f : factors) {
    out << f->tag() << ' ';
    f->writeFields(out);
    out << '\n';
  }
  out.precision(old_precision);
  out.flags(old_flags);
  if (!out) throw Error("writing the g2o file failed");
}

void writeG2o(const std::string& path, const Values& values, const std::vector<FactorPtr>& factors,
              const std::set<Key>& fixed) {
  checkWritable(values, factors, fixed);
  writeOutputFile(path, [&](std::ostream& out) { writeG2o(out, values, factors, fixed); });
}

namespace {

// Checks a pose graph for TORO / GTSAM and gives each factor's measurement.
std::vector<RelativePose> poseGraphEdges(const Values& values,
                                         const std::vector<FactorPtr>& factors, Format format,
                                         const std::set<Key>& fixed) {
  const std::string what = std::string("cannot write ") + formatName(format) + ": ";
  if (!fixed.empty())
    throw Error(what + fixed.begin()->str() + " is fixed, and the format has no FIX line");
  for (Key k : values.keys())
    if (k.kind() != kPoseKind || values.type(k) != VariableType::kPose2)
      throw Error(what + "variable " + k.str() + " is not a pose; the format holds pose graphs");
  std::vector<RelativePose> edges;
  for (const auto& f : factors) {
    if (!f) throw Error(what + "null factor");
    const std::optional<RelativePose> rp = relativePoseOf(*f);
    if (!rp || f->lossFunction())
      throw Error(what + "a " + f->tag() + " factor on " + f->keys()[0].str() +
                  (rp ? " carries a robust loss" : " is not a relative-pose measurement") +
                  ", and the format has no line for it");
    if (!values.empty() && (!values.contains(rp->from) || !values.contains(rp->to)))
      throw Error(what + "a " + f->tag() + " factor refers to a pose that has no value");
    edges.push_back(*rp);
  }
  return edges;
}

}  // namespace

void writeGraph(std::ostream& out, const Values& values, const std::vector<FactorPtr>& factors,
                Format format, const std::set<Key>& fixed) {
  if (format == Format::kG2o) return writeG2o(out, values, factors, fixed);
  if (format == Format::kAuto) throw Error("writing a graph needs a format, not auto");
  const std::vector<RelativePose> edges = poseGraphEdges(values, factors, format, fixed);
  const std::streamsize old_precision = out.precision(17);
  const std::ios_base::fmtflags old_flags = out.flags();
  out.unsetf(std::ios_base::floatfield);
  for (Key k : values.keys()) {
    const Values::Entry& e = values.entry(k);
    out << kVertex2 << ' ' << k.index() << ' ' << e.data[0] << ' ' << e.data[1] << ' ' << e.data[2]
        << '\n';
  }
  for (const auto& e : edges) {
    out << "EDGE2 " << e.from.index() << ' ' << e.to.index() << ' ' << e.measurement.x << ' '
        << e.measurement.y << ' ' << e.measurement.theta;
    if (format == Format::kToro) {
      const Eigen::Matrix3d& i = e.information;
      out << ' ' << i(0, 0) << ' ' << i(0, 1) << ' ' << i(1, 1) << ' ' << i(2, 2) << ' ' << i(0, 2)
          << ' ' << i(1, 2);
    } else {
      writeUpperTriangle(out, e.information.inverse());
    }
    out << '\n';
  }
  out.precision(old_precision);
  out.flags(old_flags);
  if (!out) throw Error(std::string("writing the ") + formatName(format) + " file failed");
}

void writeGraph(const std::string& path, const Values& values,
                const std::vector<FactorPtr>& factors, Format format, const std::set<Key>& fixed) {
  if (format == Format::kG2o) return writeG2o(path, values, factors, fixed);
  if (format == Format::kAuto) throw Error(path + ": writing a graph needs a format, not auto");
  poseGraphEdges(values, factors, format, fixed);
  writeOutputFile(path,
                  [&](std::ostream& out) { writeGraph(out, values, factors, format, fixed); });
}

}  // namespace hamal
