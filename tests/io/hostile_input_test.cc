// What a hostile user's files get from the reader with the built-in factors:
// an edge from a variable to itself, numbers whose square overflows,
// out-of-range numbers, a 10 MB token and binary garbage each give
// "file:line: reason", and the reason quotes at most a few dozen characters
// with non-printable bytes escaped, so that it fits a terminal.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "core/error.h"
#include "core/graph_io.h"
#include "core/line_tokens.h"
#include "factors/register_factors.h"

namespace hamal {
namespace {

std::string readError(const std::string& text, const std::string& name,
                      Format format = Format::kAuto) {
  Registry registry;
  registerFactors(registry);
  std::istringstream in(text);
  try {
    readGraph(in, name, registry, format);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

bool printableAscii(const std::string& text) {
  for (unsigned char c : text)
    if (c < 0x20 || c >= 0x7f) return false;
  return true;
}

const char* kPoses = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";

TEST(HostileInput, AnEdgeFromAVariableToItselfIsALineError) {
  EXPECT_EQ(readError(std::string(kPoses) + "EDGE_SE2 1 1 0 0 0 1 0 0 1 0 1\n", "self.g2o"),
            "self.g2o:3: EDGE_SE2 names pose 1 twice: a factor's variables must be distinct");
  EXPECT_EQ(readError("EDGE2 4 4 1 0 0 1 0 1 1 0 0\n", "self.toro"),
            "self.toro:1: EDGE2 names pose 4 twice: a factor's variables must be distinct");
  EXPECT_EQ(readError("ODOMETRY 2 2 1 0 0 1 0 0 1 0 1\n", "self.txt"),
            "self.txt:1: ODOMETRY names pose 2 twice: a factor's variables must be distinct");
}

TEST(HostileInput, OverflowIsOutOfRangeNotNaN) {
  const std::string msg =
      readError(std::string(kPoses) + "EDGE_SE2 0 1 1e400 0 0 1 0 0 1 0 1\n", "big.g2o");
  EXPECT_EQ(msg,
            "big.g2o:3: dx is '1e400': out of range (its magnitude must be at most 1.3e154, "
            "whose square a double holds)");
  EXPECT_NE(readError("VERTEX_SE2 0 -1e999 0 0\n", "big.g2o").find("out of range"),
            std::string::npos);
  // A literal infinity is still called what it is.
  EXPECT_NE(readError("VERTEX_SE2 0 inf 0 0\n", "big.g2o").find("NaN and infinity"),
            std::string::npos);
}

TEST(HostileInput, AMeasurementOrInformationWhoseSquareOverflowsIsRefused) {
  // dx = 1e300 gave "chi2 after: inf" and "status: ok"; information 1e300
  // gave chi2 1e271..1e295 and "ok".
  EXPECT_EQ(readError(std::string(kPoses) + "EDGE_SE2 0 1 1e300 0 0 1 0 0 1 0 1\n", "m.g2o"),
            "m.g2o:3: dx is '1e300': out of range (its magnitude must be at most 1.3e154, "
            "whose square a double holds)");
  EXPECT_EQ(
      readError(std::string(kPoses) + "EDGE_SE2 0 1 1 0 0 1e300 0 0 1e300 0 1e300\n", "i.g2o"),
      "i.g2o:3: I11 is '1e300': out of range (its magnitude must be at most 1.3e154, whose "
      "square a double holds)");
  // The largest accepted magnitude still reads.
  EXPECT_EQ(
      readError(std::string(kPoses) + "EDGE_SE2 0 1 1 0 0 1e150 0 0 1e150 0 1e150\n", "ok.g2o"),
      "");
}

TEST(HostileInput, AHugeTokenIsQuotedShort) {
  const std::string token(10 * 1000 * 1000, '7');
  const std::string msg =
      readError(std::string(kPoses) + "EDGE_SE2 0 1 " + token + "x 0 0 1 0 0 1 0 1\n", "h.g2o");
  EXPECT_LT(msg.size(), 300u) << msg.substr(0, 300);
  EXPECT_EQ(msg.rfind("h.g2o:3: dx is '7777", 0), 0u) << msg.substr(0, 300);
  EXPECT_NE(msg.find("...' (10000001 bytes), not a number"), std::string::npos) << msg;
  // An id too long for 64 bits says so.
  EXPECT_NE(readError("VERTEX_SE2 123456789012345678901234567890 0 0 0\n", "id.g2o")
                .find("not a non-negative integer id (out of range)"),
            std::string::npos);
}

TEST(HostileInput, BinaryGarbageIsEscaped) {
  std::string garbage =
      "\x7f"
      "ELF\x02\x01\x01";
  garbage += std::string(1, '\0') + "\x1b[31m\xff\xfe";
  const std::string msg = readError(garbage + " 1 2 3\n", "bin.g2o", Format::kG2o);
  EXPECT_TRUE(printableAscii(msg)) << msg;
  EXPECT_NE(msg.find("bin.g2o:1: unknown tag '\\x7fELF\\x02\\x01\\x01\\x00\\x1b[31m\\xff\\xfe'"),
            std::string::npos)
      << msg;
  // Format detection quotes the first tag the same way.
  const std::string detect = readError(garbage + "\n", "bin.dat");
  EXPECT_TRUE(printableAscii(detect)) << detect;
  EXPECT_NE(detect.find("first tag '\\x7fELF"), std::string::npos) << detect;
}

TEST(HostileInput, QuotedKeepsShortPrintableTextAsItIs) {
  EXPECT_EQ(quoted("abc"), "'abc'");
  EXPECT_EQ(quoted("tab\there"), "'tab\\x09here'");
  EXPECT_EQ(quoted(std::string(50, 'a'), 4), "'aaaa...' (50 bytes)");
}

}  // namespace
}  // namespace hamal
