// Format::kAuto (graph_io.h): the file name first, then the tags; EDGE2 in a
// file of any other name is refused, because TORO stores an information
// matrix where GTSAM stores a covariance and guessing would silently weight
// every edge wrongly.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "core/graph_io.h"
#include "tests/io/fake_factors.h"

namespace hamal::io_test {
namespace {

TEST(FormatDetection, NamesAndParsing) {
  for (Format f : {Format::kAuto, Format::kG2o, Format::kToro, Format::kGtsam})
    EXPECT_EQ(parseFormat(formatName(f)), f);
  EXPECT_HAS(errorOf([] { parseFormat("G2O"); }),
             "unknown file format 'G2O'; expected auto, g2o, toro or gtsam");
}

// Six numbers that are SPD both as TORO information (I11 I12 I22 I33 I13 I23)
// and as a GTSAM covariance (c11 c12 c13 c22 c23 c33), giving different
// information matrices: the factor tells which reading the reader chose.
const char* kEdge2 = "EDGE2 0 1 1 0 0 4 0 2 4 0 2\n";

Eigen::Matrix3d toroInformation() {
  return (Eigen::Matrix3d() << 4, 0, 0, 0, 2, 2, 0, 2, 4).finished();
}
Eigen::Matrix3d gtsamInformation() {
  return (Eigen::Matrix3d() << 4, 0, 2, 0, 4, 0, 2, 0, 2).finished().inverse();
}

Eigen::Matrix3d edge2Information(const std::string& text, const std::string& name, Format format) {
  const Graph g = readText(text, name, fakeRegistry(), format);
  for (const auto& f : g.factors)
    if (auto* b = dynamic_cast<const FakeBetween*>(f.get())) return b->info_;
  ADD_FAILURE() << "no EDGE2 factor";
  return Eigen::Matrix3d::Zero();
}

TEST(FormatDetection, TheNumbersReallyDisagree) {
  EXPECT_FALSE(toroInformation().isApprox(gtsamInformation(), 1e-3));
}

TEST(FormatDetection, ByFileName) {
  EXPECT_TRUE(edge2Information(kEdge2, "M3500.toro", Format::kAuto).isApprox(toroInformation()));
  EXPECT_TRUE(
      edge2Information(kEdge2, "dir.x/M3500.TORO", Format::kAuto).isApprox(toroInformation()));
  // A .g2o name means g2o even if the tags are TORO's: EDGE2 is then unknown.
  EXPECT_HAS(errorOf([] { readText(kEdge2, "a.g2o", fakeRegistry()); }),
             "a.g2o:1: unknown tag 'EDGE2' for format g2o (from the .g2o file name)");
}

TEST(FormatDetection, ByTags) {
  const Registry r = fakeRegistry();
  EXPECT_EQ(readText("VERTEX_SE2 0 0 0 0\n", "a.txt", r).initial.size(), 1u);
  EXPECT_EQ(readText("# x\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n", "a.dat", r).factors.size(), 1u);
  // ODOMETRY or LANDMARK make the file GTSAM's, so its EDGE2 is a covariance.
  EXPECT_TRUE(
      edge2Information(std::string("LANDMARK 0 5 1 1 1 0 1\n") + kEdge2, "v.txt", Format::kAuto)
          .isApprox(gtsamInformation()));
  EXPECT_HAS(errorOf([&] { readText("VERTEX_SE2 0 0 0 0\nEDGE_SE3 0 0\n", "a.txt", r); }),
             "a.txt:2: unknown tag 'EDGE_SE3' for format g2o (from its VERTEX_SE2 "
             "line 1)");
}

TEST(FormatDetection, Edge2InAnotherFileIsAmbiguous) {
  const std::string msg = errorOf([] {
    readText(std::string("# w-world\nVERTEX2 0 0 0 0\n") + kEdge2, "w20000.txt", fakeRegistry());
  });
  EXPECT_HAS(msg, "w20000.txt:3: EDGE2 lines are ambiguous");
  EXPECT_HAS(msg, "--format=toro or --format=gtsam");
  EXPECT_HAS(msg, "INFORMATION");
  EXPECT_HAS(msg, "COVARIANCE");
  // g2o's vertex lines (which GTSAM's loader accepts too) do not settle it.
  EXPECT_HAS(errorOf([] {
               readText(std::string("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\n") + kEdge2, "v.txt",
                        fakeRegistry());
             }),
             "v.txt:3: EDGE2 lines are ambiguous");
  // Said explicitly, either reading is taken as asked.
  EXPECT_TRUE(edge2Information(kEdge2, "w20000.txt", Format::kToro).isApprox(toroInformation()));
  EXPECT_TRUE(edge2Information(kEdge2, "w20000.txt", Format::kGtsam).isApprox(gtsamInformation()));
  // An explicit format also overrides the file name.
  EXPECT_TRUE(edge2Information(kEdge2, "M3500.toro", Format::kGtsam).isApprox(gtsamInformation()));
}

TEST(FormatDetection, NoKnownTagAtAll) {
  const std::string msg =
      errorOf([] { readText("\nFOO 1 2\nBAR 3\n", "odd.txt", fakeRegistry()); });
  EXPECT_HAS(msg, "odd.txt:2: cannot tell the file's format");
  EXPECT_HAS(msg, "'FOO'");
  EXPECT_HAS(msg, "--format=g2o");
  EXPECT_HAS(msg, "toro: EDGE2, VERTEX2");
}

TEST(FormatDetection, APluginsG2oTagCountsAsG2o) {
  Registry r = fakeRegistry();
  r.addFactor({"g2o", "EDGE_RANGE", "plugin", [](LineTokens& t) -> FactorPtr {
                 return parseBetween(t, MatrixLayout::kG2oInformation);
               }});
  EXPECT_EQ(readText("EDGE_RANGE 0 1 1 0 0 1 0 0 1 0 1\n", "p.log", r).factors.size(), 1u);
}

}  // namespace
}  // namespace hamal::io_test
