// Every kind of bad input the reader refuses (graph_io.h), each asserting
// that the message says where (file:line) and why: the project's rule is
// that nothing is skipped silently and every error can be acted on.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "core/graph_io.h"
#include "tests/io/fake_factors.h"

namespace hamal::io_test {
namespace {

std::string readError(const std::string& text, const std::string& name,
                      Format format = Format::kAuto) {
  const Registry r = fakeRegistry();
  return errorOf([&] { readText(text, name, r, format); });
}

const char* kTwoPoses = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";

TEST(GraphReadErrors, MissingFile) {
  const std::string path = ::testing::TempDir() + "no_such_graph.g2o";
  const std::string msg = errorOf([&] { readGraph(path, fakeRegistry()); });
  EXPECT_HAS(msg, path + ": file does not exist");
}

TEST(GraphReadErrors, DirectoryIsNotAFile) {
  const std::string dir = ::testing::TempDir() + "graph_dir.g2o";
  std::filesystem::create_directories(dir);
  EXPECT_HAS(errorOf([&] { readGraph(dir, fakeRegistry()); }), "is a directory");
  std::filesystem::remove(dir);
}

TEST(GraphReadErrors, EmptyFile) {
  EXPECT_EQ(readError("", "e.g2o"), "e.g2o: empty file: no vertex and no factor");
  // Comments and blank lines only is empty too, whatever the format.
  EXPECT_EQ(readError("# nothing\n\n   \n", "e.txt"), "e.txt: empty file: no vertex and no factor");
}

TEST(GraphReadErrors, TruncatedVertexLine) {
  const std::string msg = readError("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0\n", "t.g2o");
  EXPECT_HAS(msg, "t.g2o:2: ");
  EXPECT_HAS(msg, "truncated");
  EXPECT_HAS(msg, "theta");
  EXPECT_HAS(readError("VERTEX_XY 4\n", "t.g2o"), "t.g2o:1: VERTEX_XY line is truncated");
  EXPECT_HAS(readError("VERTEX2 4 1 2\n", "t.toro"), "t.toro:1: VERTEX2 line is truncated");
}

TEST(GraphReadErrors, VertexLineWithExtraFields) {
  const std::string msg = readError("VERTEX_XY 0 1 2 3\n", "x.g2o");
  EXPECT_HAS(msg, "x.g2o:1: VERTEX_XY line has 4 fields, expected 3");
}

TEST(GraphReadErrors, MalformedNumbersAndIds) {
  EXPECT_HAS(readError("VERTEX_SE2 0 1.0x 0 0\n", "m.g2o"), "m.g2o:1: x is '1.0x', not a number");
  EXPECT_HAS(readError("VERTEX_SE2 -3 0 0 0\n", "m.g2o"),
             "m.g2o:1: id is '-3', not a non-negative integer id");
  EXPECT_HAS(readError("VERTEX_SE2 2.5 0 0 0\n", "m.g2o"), "not a non-negative");
  EXPECT_HAS(readError("VERTEX_SE2 72057594037927936 0 0 0\n", "m.g2o"),
             "m.g2o:1: id 72057594037927936 is too large");
}

TEST(GraphReadErrors, TruncatedOrMalformedEdge) {
  std::string msg = readError(std::string(kTwoPoses) + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n", "e.g2o");
  EXPECT_HAS(msg, "e.g2o:3: EDGE_SE2 line is truncated");
  EXPECT_HAS(msg, "I33 is missing");
  msg = readError(std::string(kTwoPoses) + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1 9\n", "e.g2o");
  EXPECT_HAS(msg, "e.g2o:3: EDGE_SE2 line has 12 fields, expected 11");
}

TEST(GraphReadErrors, NanAndInfinity) {
  EXPECT_HAS(readError("VERTEX_SE2 0 nan 0 0\n", "n.g2o"),
             "n.g2o:1: x is 'nan': NaN and infinity are not accepted");
  EXPECT_HAS(readError(std::string(kTwoPoses) + "EDGE_SE2 0 1 1 0 0 inf 0 0 1 0 1\n", "n.g2o"),
             "n.g2o:3: I11 is 'inf': NaN and infinity");
}

TEST(GraphReadErrors, InformationNotPositiveDefinite) {
  std::string msg =
      readError(std::string(kTwoPoses) + "EDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n", "p.g2o");
  EXPECT_HAS(msg, "p.g2o:3: the information matrix is not symmetric positive definite");
  // A covariance is checked before it is inverted.
  msg = readError("ODOMETRY 0 1 1 0 0 1 2 0 1 0 1\n", "p.txt");
  EXPECT_HAS(msg, "p.txt:1: the covariance matrix is not symmetric positive definite");
  msg = readError("LANDMARK 0 1 1 0 0 0 1\n", "p.txt");
  EXPECT_HAS(msg, "p.txt:1: the covariance matrix is not");
}

TEST(GraphReadErrors, UnknownTagListsTheFormatsTags) {
  const std::string msg = readError(std::string(kTwoPoses) + "EDGE_SE3 0 1\n", "u.g2o");
  EXPECT_HAS(msg, "u.g2o:3: unknown tag 'EDGE_SE3' for format g2o");
  EXPECT_HAS(msg, "from the .g2o file name");
  EXPECT_HAS(msg, "known tags: EDGE_SE2, EDGE_SE2_XY, FIX, VERTEX_SE2, VERTEX_XY");
  // TORO knows no g2o vertex.
  EXPECT_HAS(readError("VERTEX_SE2 0 0 0 0\n", "u.toro"),
             "u.toro:1: unknown tag 'VERTEX_SE2' for format toro (from the .toro file "
             "name); known tags: EDGE2, VERTEX2");
}

TEST(GraphReadErrors, DuplicateVertexId) {
  EXPECT_HAS(readError("VERTEX_SE2 5 0 0 0\nVERTEX_SE2 5 1 0 0\n", "d.g2o"),
             "d.g2o:2: duplicate vertex id 5: line 1 already defines it (VERTEX_SE2)");
  // g2o has one id space: a pose and a landmark may not share an id.
  const std::string msg = readError("VERTEX_SE2 5 0 0 0\n# c\nVERTEX_XY 5 1 0\n", "d.g2o");
  EXPECT_HAS(msg,
             "d.g2o:3: duplicate vertex id 5: line 1 already defines it as a "
             "VERTEX_SE2");
  EXPECT_HAS(msg, "one id space");
  EXPECT_HAS(readError("VERTEX2 1 0 0 0\nVERTEX2 1 0 0 0\n", "d.toro"),
             "d.toro:2: duplicate vertex id 1");
}

TEST(GraphReadErrors, EdgeToAVariableNoVertexDefines) {
  const std::string msg = readError(std::string(kTwoPoses) +
                                        "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"
                                        "EDGE_SE2 1 7 1 0 0 1 0 0 1 0 1\n",
                                    "v.g2o");
  EXPECT_HAS(msg, "v.g2o:4: EDGE_SE2 refers to pose 7, which no VERTEX line defines");
}

TEST(GraphReadErrors, EdgeToAVertexOfAnotherKind) {
  const std::string msg =
      readError("VERTEX_SE2 0 0 0 0\nVERTEX_XY 5 1 1\nEDGE_SE2 0 5 1 0 0 1 0 0 1 0 1\n", "k.g2o");
  EXPECT_HAS(msg, "k.g2o:3: EDGE_SE2 refers to pose 5 but 5 is a VERTEX_XY (line 2)");
  EXPECT_HAS(
      readError("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 5 1 1 0\nEDGE_SE2_XY 0 5 1 0 1 0 1\n", "k.g2o"),
      "k.g2o:3: EDGE_SE2_XY refers to landmark 5 but 5 is a VERTEX_SE2");
}

TEST(GraphReadErrors, WithoutVerticesG2oStillHasOneIdSpace) {
  // The edges define the variables, but id 1 cannot be a pose and a landmark.
  const std::string msg =
      readError("EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2_XY 0 1 1 0 1 0 1\n", "s.g2o");
  EXPECT_HAS(msg, "s.g2o:2: EDGE_SE2_XY refers to landmark 1 but line 1 uses 1 as a pose");
}

TEST(GraphReadErrors, FixOfAnUndefinedId) {
  EXPECT_HAS(readError(std::string(kTwoPoses) + "FIX 9\n", "f.g2o"),
             "f.g2o:3: FIX refers to id 9, which no vertex defines");
  EXPECT_HAS(readError("EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nFIX 2\n", "f.g2o"),
             "f.g2o:2: FIX refers to id 2, which no vertex or edge names");
  EXPECT_HAS(readError(std::string(kTwoPoses) + "FIX\n", "f.g2o"),
             "f.g2o:3: FIX line names no vertex id");
}

TEST(GraphReadErrors, SloppyFactorKindsAreCaughtToo) {
  // A plugin's parse function that stops early, or throws without saying
  // where, still gives a complete "file:line: reason".
  Registry r;
  r.addFactor({"g2o", "EDGE_LAZY", "reads one id", [](LineTokens& t) -> FactorPtr {
                 const Key a = X(t.id("a")), b = X(t.id("b"));
                 return std::make_shared<FakeBetween>(a, b, Eigen::Vector3d::Zero(),
                                                      Eigen::Matrix3d::Identity());
               }});
  r.addFactor({"g2o", "EDGE_THROWS", "throws",
               [](LineTokens&) -> FactorPtr { throw std::runtime_error("bad thing"); }});
  r.addFactor({"g2o", "EDGE_NULL", "returns null", [](LineTokens&) -> FactorPtr { return {}; }});
  auto error = [&](const std::string& text) {
    return errorOf([&] { readText(text, "p.g2o", r); });
  };
  EXPECT_HAS(error("EDGE_LAZY 0 1 2 3\n"), "p.g2o:1: EDGE_LAZY line has 4 fields, expected 2");
  EXPECT_HAS(error("\nEDGE_THROWS\n"), "p.g2o:2: EDGE_THROWS: bad thing");
  EXPECT_HAS(error("EDGE_NULL\n"), "p.g2o:1: EDGE_NULL: the factor kind's parse");
}

}  // namespace
}  // namespace hamal::io_test
