// Tests of the public Jacobian check (core/jacobian_check.h): it must pass a
// correct analytic Jacobian and catch wrong ones, including small errors, a
// wrong block and an inconsistent per-block evaluation; and it must report
// where the error is.
#include "core/jacobian_check.h"

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace hamal {
namespace {

// r = [ x0 * sin(x2) + y0^2 ; cos(x1) * y1 ] on a Pose2 x and a Point2 y, with
// its Jacobian made wrong on purpose in one of several ways.
enum class Mistake { kNone, kSign, kSmall, kWrongColumn, kBlockAlone, kNaN };

class TestCost : public ceres::SizedCostFunction<2, 3, 2> {
 public:
  explicit TestCost(Mistake mistake) : mistake_(mistake) {}

  bool Evaluate(double const* const* p, double* r, double** j) const override {
    const double* x = p[0];
    const double* y = p[1];
    r[0] = x[0] * std::sin(x[2]) + y[0] * y[0];
    r[1] = std::cos(x[1]) * y[1];
    if (!j) return true;
    if (j[0]) {
      double* a = j[0];  // 2x3 row-major
      a[0] = std::sin(x[2]);
      a[1] = 0.0;
      a[2] = x[0] * std::cos(x[2]);
      a[3] = 0.0;
      a[4] = -std::sin(x[1]) * y[1];
      a[5] = 0.0;
      if (mistake_ == Mistake::kSign) a[4] = -a[4];
      if (mistake_ == Mistake::kSmall) a[2] *= 1.0 + 1e-4;
      if (mistake_ == Mistake::kNaN) a[5] = std::nan("");
    }
    if (j[1]) {
      double* b = j[1];  // 2x2 row-major
      b[0] = 2.0 * y[0];
      b[1] = 0.0;
      b[2] = 0.0;
      b[3] = std::cos(x[1]);
      if (mistake_ == Mistake::kWrongColumn) std::swap(b[0], b[1]);
      // Right when both blocks are asked for, wrong when Ceres asks for this
      // block alone (as it does when the pose is held constant).
      if (mistake_ == Mistake::kBlockAlone && !j[0]) b[3] = 0.0;
    }
    return true;
  }

 private:
  Mistake mistake_;
};

class TestFactor : public Factor {
 public:
  explicit TestFactor(Mistake mistake)
      : Factor({X(1), L(2)}, std::make_unique<TestCost>(mistake)) {}
  std::string tag() const override { return "TEST"; }
  void writeFields(std::ostream&) const override {}
};

TEST(JacobianCheck, PassesACorrectJacobian) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kNone));
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
  EXPECT_LT(r.max_rel_error, 1e-7) << r.report;
  EXPECT_NE(r.report.find("OK"), std::string::npos);
}

TEST(JacobianCheck, CatchesASignError) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kSign));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.worst.block, 0);
  EXPECT_EQ(r.worst.row, 1);
  EXPECT_EQ(r.worst.col, 1);
  EXPECT_NEAR(r.worst.analytic, -r.worst.numeric, 1e-6 * std::abs(r.worst.numeric));
  EXPECT_NE(r.report.find("FAILED"), std::string::npos) << r.report;
  EXPECT_NE(r.report.find("block 0 (x1)"), std::string::npos) << r.report;
  EXPECT_NE(r.report.find("State of the worst entry: x1 = ["), std::string::npos) << r.report;
}

TEST(JacobianCheck, CatchesARelativeErrorOf1e4) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kSmall));
  EXPECT_FALSE(r.ok) << r.report;
  EXPECT_EQ(r.worst.block, 0);
  EXPECT_EQ(r.worst.row, 0);
  EXPECT_EQ(r.worst.col, 2);
  EXPECT_GT(r.max_rel_error, 1e-5);
}

TEST(JacobianCheck, CatchesAWrongEntryInTheSecondBlock) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kWrongColumn));
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.worst.block, 1);
  EXPECT_EQ(r.worst.row, 0);
  EXPECT_NE(r.report.find("(l2)"), std::string::npos) << r.report;
}

TEST(JacobianCheck, CatchesABlockThatDiffersWhenEvaluatedAlone) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kBlockAlone));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.report.find("block 1 alone"), std::string::npos) << r.report;
}

TEST(JacobianCheck, CatchesNaN) {
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kNaN));
  EXPECT_FALSE(r.ok) << r.report;
  EXPECT_EQ(r.worst.col, 2);
}

TEST(JacobianCheck, UsesTheUsersSamplerAndFilter) {
  int calls = 0;
  JacobianCheckOptions options;
  options.trials = 50;
  // Reject half of the states: the check must resample, not skip.
  options.accept = [](const Values& v) { return v.pose(X(1)).x > 0.0; };
  const JacobianCheckResult r = checkJacobians(
      TestFactor(Mistake::kNone),
      [&calls](std::mt19937_64& rng) {
        ++calls;
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        Values v;
        v.insert(X(1), Pose2(u(rng), u(rng), u(rng)));
        v.insert(L(2), Point2(u(rng), u(rng)));
        return v;
      },
      options);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 50);
  EXPECT_GT(r.rejected, 0);
  EXPECT_EQ(calls, r.trials + r.rejected);
  EXPECT_GT(r.worst.state.pose(X(1)).x, 0.0);
}

TEST(JacobianCheck, FailsWhenTheFilterRejectsEverything) {
  JacobianCheckOptions options;
  options.accept = [](const Values&) { return false; };
  options.max_resamples = 10;
  const JacobianCheckResult r = checkJacobians(TestFactor(Mistake::kNone), options);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.trials, 0);
  EXPECT_EQ(r.rejected, 11);
  EXPECT_NE(r.report.find("no acceptable state"), std::string::npos) << r.report;
}

TEST(JacobianCheck, RejectsASamplerThatDoesNotFitTheFactor) {
  const auto missing = [](std::mt19937_64&) {
    Values v;
    v.insert(X(1), Pose2(1, 2, 3));
    return v;
  };
  EXPECT_THROW(checkJacobians(TestFactor(Mistake::kNone), missing), Error);
  const auto wrong_type = [](std::mt19937_64&) {
    Values v;
    v.insert(X(1), Pose2(1, 2, 3));
    v.insert(L(2), Pose2(1, 2, 3));
    return v;
  };
  EXPECT_THROW(checkJacobians(TestFactor(Mistake::kNone), wrong_type), Error);
}

TEST(JacobianCheck, DefaultStatesAreInTheDocumentedBox) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 1000; ++i) {
    const Values::Entry p = randomEntry(VariableType::kPose2, rng);
    EXPECT_LE(std::abs(p.data[0]), 10.0);
    EXPECT_LE(std::abs(p.data[1]), 10.0);
    EXPECT_GT(p.data[2], -M_PI);
    EXPECT_LE(p.data[2], M_PI);
    const Values::Entry l = randomEntry(VariableType::kPoint2, rng);
    EXPECT_EQ(l.type, VariableType::kPoint2);
    EXPECT_LE(std::abs(l.data[0]), 10.0);
  }
}

TEST(JacobianCheck, IsDeterministicForASeed) {
  const JacobianCheckResult a = checkJacobians(TestFactor(Mistake::kSmall));
  const JacobianCheckResult b = checkJacobians(TestFactor(Mistake::kSmall));
  EXPECT_EQ(a.max_rel_error, b.max_rel_error);
  EXPECT_EQ(a.worst.trial, b.worst.trial);
}

}  // namespace
}  // namespace hamal
