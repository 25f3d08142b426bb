// The file registrations of the built-in factors (factors/register_factors.cc):
// every (format, tag) parses a good line, fails on a truncated line, a NaN, a
// non-SPD matrix, an extra field and a bad id with "file:line: reason", and a
// factor written with writeFields reads back identical.
#include "factors/register_factors.h"

#include <gtest/gtest.h>

#include <set>
#include <sstream>

#include "core/error.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"

namespace hamal {
namespace {

struct Case {
  std::string format, tag, fields;
  std::vector<Key> keys;
  int ids;          // leading id fields
  int matrix_size;  // trailing matrix fields
};

std::vector<Case> cases() {
  return {
      {"g2o", "EDGE_SE2", "0 1 1.5 -0.3 0.4 100 5 1 50 2 300", {X(0), X(1)}, 2, 6},
      {"toro", "EDGE2", "0 1 1.5 -0.3 0.4 100 5 50 300 1 2", {X(0), X(1)}, 2, 6},
      {"gtsam", "EDGE2", "3 2 0.09 0.08 -0.02 0.01 0 0 0.04 0 0.25", {X(3), X(2)}, 2, 6},
      {"gtsam", "ODOMETRY", "0 1 1.0 0.0 0.1 0.01 0.001 0 0.04 0 0.25", {X(0), X(1)}, 2, 6},
      {"g2o", "EDGE_SE2_PRIOR", "3 1 2 0.5 100 5 1 50 2 300", {X(3)}, 1, 6},
      {"g2o", "EDGE_SE2_XY", "4 5 11.5 -3.2 6 -1.5 2", {X(4), L(5)}, 2, 3},
      {"gtsam", "LANDMARK", "4 5 11.5387 -3.2007 0.4 0 0.4", {X(4), L(5)}, 2, 3},
      {"g2o", "EDGE_SE2_RANGE_BEARING", "2 7 5.5 0.3 4 0.5 30", {X(2), L(7)}, 2, 3},
      {"g2o", "EDGE_SE2_POSITION", "2 1.5 -2.5 3 1 5", {X(2)}, 1, 3},
      {"g2o", "EDGE_XY_PRIOR", "7 1.5 -2.5 3 1 5", {L(7)}, 1, 3},
      {"g2o", "EDGE_SE2_L2G", "4 9 1 2 0.3 1.5 -0.3 0.4 100 5 1 50 2 300", {X(4)}, 2, 6},
  };
}

class RegisterFactorsTest : public ::testing::Test {
 protected:
  RegisterFactorsTest() { registerFactors(registry_); }

  FactorPtr parse(const std::string& format, const std::string& line) const {
    LineTokens tokens = LineTokens::split("f.g2o", 7, line);
    const FactorInfo* info = registry_.findFactor(format, tokens.tag());
    if (!info) throw std::logic_error("no factor " + format + " " + tokens.tag());
    return info->parse(tokens);
  }

  // The message of the error parsing `line` throws, "" when it parses.
  std::string parseError(const std::string& format, const std::string& line) const {
    try {
      parse(format, line);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }

  Registry registry_;
};

std::vector<std::string> split(const std::string& s) {
  std::istringstream is(s);
  std::vector<std::string> out;
  for (std::string t; is >> t;) out.push_back(t);
  return out;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& t : v) s += (s.empty() ? "" : " ") + t;
  return s;
}

TEST_F(RegisterFactorsTest, RegistersTheDocumentedTags) {
  std::set<std::pair<std::string, std::string>> expected, got;
  for (const Case& c : cases()) expected.insert({c.format, c.tag});
  // Its line wraps another line: max_mixture_factor_test.cc tests it.
  expected.insert({"g2o", "EDGE_MAXMIX"});
  for (const FactorInfo* f : registry_.factors()) {
    got.insert({f->format, f->tag});
    EXPECT_FALSE(f->description.empty()) << f->tag;
  }
  EXPECT_EQ(got, expected);
  EXPECT_THROW(registerFactors(registry_), Error);  // every name is taken
}

TEST_F(RegisterFactorsTest, GoodLinesParseWithTheirKeys) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.format + " " + c.tag);
    const FactorPtr f = parse(c.format, c.tag + " " + c.fields);
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->keys(), c.keys);
  }
}

TEST_F(RegisterFactorsTest, BadLinesFailWithLineAndReason) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.format + " " + c.tag);
    const std::vector<std::string> fields = split(c.fields);
    const auto expectError = [&](std::vector<std::string> f, const std::string& reason) {
      const std::string message = parseError(c.format, c.tag + " " + join(f));
      EXPECT_EQ(message.rfind("f.g2o:7: ", 0), 0u) << "'" << message << "'";
      EXPECT_NE(message.find(reason), std::string::npos) << "'" << message << "'";
    };
    std::vector<std::string> f = fields;
    f.pop_back();
    expectError(f, "truncated");
    expectError({fields.begin(), fields.begin() + c.ids}, "truncated");

    f = fields;
    f[c.ids] = "nan";
    expectError(f, "NaN");
    f = fields;
    f.back() = "inf";
    expectError(f, "NaN and infinity");
    f = fields;
    f[c.ids + 1] = "1.5x";
    expectError(f, "not a number");

    f = fields;
    f[fields.size() - c.matrix_size] = "-1";  // a11 < 0
    expectError(f, "not symmetric positive definite");
    f = fields;
    for (int i = 0; i < c.matrix_size; ++i) f[fields.size() - 1 - i] = "0";
    expectError(f, "not symmetric positive definite");

    f = fields;
    f.push_back("1");
    expectError(f, "expected " + std::to_string(fields.size()));

    f = fields;
    f[0] = "-1";
    expectError(f, "not a non-negative integer id");
    f[0] = "2.5";
    expectError(f, "not a non-negative integer id");
    f[0] = "72057594037927936";  // 2^56: would alias another key
    expectError(f, "larger than the largest id");
  }
}

TEST_F(RegisterFactorsTest, WriteFieldsThenParseGivesTheSameFactor) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.format + " " + c.tag);
    const FactorPtr original = parse(c.format, c.tag + " " + c.fields);
    std::ostringstream os;
    os.precision(3);  // the factor must not depend on the caller's precision
    os << std::fixed;
    os << original->tag() << ' ';
    original->writeFields(os);
    EXPECT_EQ(os.precision(), 3);  // and must leave it as it was
    EXPECT_TRUE(os.flags() & std::ios_base::fixed);
    // Whatever format it came from, a factor is written as g2o.
    const FactorPtr copy = parse("g2o", os.str());
    EXPECT_TRUE(original->equals(*copy, 0.0));
    std::ostringstream again;
    copy->writeFields(again);
    std::ostringstream first;
    original->writeFields(first);
    EXPECT_EQ(again.str(), first.str());
  }
}

TEST_F(RegisterFactorsTest, FullPrecisionRoundTripOfArbitraryDoubles) {
  Eigen::Matrix3d info;
  info << 1.0 / 3.0, 0.1, 1e-7, 0.1, 2.0 / 7.0, 0.0, 1e-7, 0.0, 123456.789012345;
  const BetweenFactor f(X(10), X(11), Pose2(1.0 / 3.0, -2.0 / 3.0, M_PI / 7.0), info);
  std::ostringstream os;
  os << f.tag() << ' ';
  f.writeFields(os);
  EXPECT_TRUE(f.equals(*parse("g2o", os.str()), 0.0));
}

TEST_F(RegisterFactorsTest, FormatsStoreTheMatrixTheirOwnWay) {
  // The same information in g2o order and in TORO order. The parsed factors
  // are held by name: a raw pointer into a temporary shared_ptr dangles.
  const FactorPtr g2o_factor = parse("g2o", "EDGE_SE2 0 1 1.5 -0.3 0.4 100 5 1 50 2 300");
  const FactorPtr toro_factor = parse("toro", "EDGE2 0 1 1.5 -0.3 0.4 100 5 50 300 1 2");
  const auto* g2o = dynamic_cast<const BetweenFactor*>(g2o_factor.get());
  const auto* toro = dynamic_cast<const BetweenFactor*>(toro_factor.get());
  ASSERT_TRUE(g2o && toro);
  Eigen::Matrix3d expected;
  expected << 100, 5, 1, 5, 50, 2, 1, 2, 300;
  EXPECT_EQ(g2o->information(), expected);
  EXPECT_EQ(toro->information(), expected);

  // GTSAM gives the covariance (w20000.txt, victoria_park.txt).
  const FactorPtr gtsam_factor =
      parse("gtsam", "EDGE2 0 1 0.09 0.08 -0.02 0.01 0.001 0.002 0.04 0.003 0.25");
  const auto* gtsam = dynamic_cast<const BetweenFactor*>(gtsam_factor.get());
  ASSERT_TRUE(gtsam);
  Eigen::Matrix3d cov;
  cov << 0.01, 0.001, 0.002, 0.001, 0.04, 0.003, 0.002, 0.003, 0.25;
  EXPECT_TRUE((gtsam->information() * cov).isIdentity(1e-12));
  EXPECT_EQ(gtsam->information(), gtsam->information().transpose());
  const FactorPtr landmark_factor = parse("gtsam", "LANDMARK 4 5 11.5387 -3.2007 0.4 0 0.4");
  const auto* landmark = dynamic_cast<const PosePointFactor*>(landmark_factor.get());
  ASSERT_TRUE(landmark);
  EXPECT_NEAR(landmark->information()(0, 0), 2.5, 1e-12);
  EXPECT_NEAR(landmark->information()(1, 1), 2.5, 1e-12);
  EXPECT_EQ(landmark->information()(0, 1), 0.0);
  EXPECT_EQ(landmark->measurement(), Point2(11.5387, -3.2007));
}

}  // namespace
}  // namespace hamal
