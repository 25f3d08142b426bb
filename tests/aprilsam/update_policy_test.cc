// Tests of AprilSAM's batch decision (thesis sec. 3.4.4, Alg. 3.1): each of
// the three criteria, the periodic and incremental modes, option parsing and
// validation, and the flop estimate the deterministic cost uses.
#include "backends/aprilsam/update_policy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "backends/aprilsam/factorization_cost.h"
#include "core/error.h"

namespace hamal::aprilsam {
namespace {

UpdatePolicy policy(const std::map<std::string, std::string>& given) {
  return UpdatePolicy(
      UpdatePolicy::fromOptions(Options("aprilsam", UpdatePolicy::optionSpecs(), given)));
}

UpdateCosts costs(double incremental, double batch, long n_lc) {
  UpdateCosts c;
  c.incremental = incremental;
  c.batch = batch;
  c.possible_loop_closure_nodes = n_lc;
  return c;
}

TEST(UpdatePolicy, DefaultsAreTheDocumentedOnes) {
  const UpdatePolicyOptions o =
      UpdatePolicy::fromOptions(Options("aprilsam", UpdatePolicy::optionSpecs(), {}));
  EXPECT_EQ(o.mode, UpdatePolicyOptions::Mode::kAdaptive);
  EXPECT_EQ(o.period, 10);
  EXPECT_DOUBLE_EQ(o.delta_t, 0.1);
  EXPECT_EQ(o.nl_t, 100);
  EXPECT_DOUBLE_EQ(o.big_delta_t, 10.0);
  EXPECT_EQ(o.cost, UpdatePolicyOptions::Cost::kDeterministic);
  for (const OptionSpec& spec : UpdatePolicy::optionSpecs()) EXPECT_FALSE(spec.help.empty());
}

TEST(UpdatePolicy, FirstUpdateIsBatchInEveryMode) {
  for (const char* mode : {"adaptive", "periodic", "incremental"}) {
    const UpdateDecision d = policy({{"mode", mode}}).decide(0, 0, 0.0, UpdateCosts());
    EXPECT_TRUE(d.batch) << mode;
    EXPECT_EQ(d.reason, "first update");
  }
}

TEST(UpdatePolicy, QuietStepIsIncremental) {
  const UpdateDecision d = policy({}).decide(7, 3, 0.5, costs(1.0, 100.0, 3));
  EXPECT_FALSE(d.batch);
  EXPECT_NE(d.reason.find("no criterion met"), std::string::npos) << d.reason;
}

TEST(UpdatePolicy, CriterionOneManyMovedNodes) {
  const UpdatePolicy p = policy({{"nl_t", "100"}});
  EXPECT_FALSE(p.decide(5, 99, 0.1, costs(1, 100, 1)).batch);
  const UpdateDecision d = p.decide(5, 123, 0.1, costs(1, 100, 1));
  EXPECT_TRUE(d.batch);
  EXPECT_EQ(d.reason, "|L|=123 >= NL_T=100");
  EXPECT_TRUE(p.decide(5, 100, 0.1, costs(1, 100, 1)).batch);  // Alg. 3.1 uses >=
}

TEST(UpdatePolicy, CriterionTwoLargeStateChange) {
  const UpdatePolicy p = policy({{"big_delta_t", "10"}});
  EXPECT_FALSE(p.decide(5, 0, 9.99, costs(1, 100, 1)).batch);
  const UpdateDecision d = p.decide(5, 0, 12.3, costs(1, 100, 1));
  EXPECT_TRUE(d.batch);
  EXPECT_EQ(d.reason, "||dx||=12.3 >= Delta_T=10");
  const UpdateDecision nan = p.decide(5, 0, std::nan(""), costs(1, 100, 1));
  EXPECT_TRUE(nan.batch);
  EXPECT_EQ(nan.reason, "||dx||=nan >= Delta_T=10");
  EXPECT_TRUE(p.decide(5, 0, std::numeric_limits<double>::infinity(), costs(1, 100, 1)).batch);
}

TEST(UpdatePolicy, CriterionThreeIncrementalCostTimesLoopClosureNodes) {
  const UpdatePolicy p = policy({});
  EXPECT_FALSE(p.decide(5, 0, 0.1, costs(2.0, 10.0, 4)).batch);       // 8 < 10
  const UpdateDecision d = p.decide(5, 0, 0.1, costs(2.0, 10.0, 5));  // 10 >= 10
  EXPECT_TRUE(d.batch);
  EXPECT_EQ(d.reason.rfind("incremental cost x n_lc >= batch cost", 0), 0u) << d.reason;
  EXPECT_NE(d.reason.find("2 x 5 >= 10"), std::string::npos) << d.reason;
  // No batch cost measured yet: the comparison has nothing to compare with.
  EXPECT_FALSE(p.decide(5, 0, 0.1, costs(2.0, 0.0, 5)).batch);
  // No node near the newest pose: no loop closure is expected.
  EXPECT_FALSE(p.decide(5, 0, 0.1, costs(1e9, 1.0, 0)).batch);
}

TEST(UpdatePolicy, CriteriaCheckedInTheThesisOrder) {
  const UpdatePolicy p = policy({});
  EXPECT_EQ(p.decide(5, 500, 50.0, costs(10, 1, 5)).reason, "|L|=500 >= NL_T=100");
  EXPECT_EQ(p.decide(5, 0, 50.0, costs(10, 1, 5)).reason, "||dx||=50 >= Delta_T=10");
}

TEST(UpdatePolicy, PeriodicIgnoresTheAdaptiveCriteria) {
  const UpdatePolicy p = policy({{"mode", "periodic"}, {"period", "50"}});
  int batches = 0;
  for (long step = 1; step <= 200; ++step) {
    const UpdateDecision d = p.decide(step, 1000, 1e6, costs(1e9, 1, 100));
    if (d.batch) {
      ++batches;
      EXPECT_EQ(step % 50, 0);
      EXPECT_EQ(d.reason, "periodic k=50");
    }
  }
  EXPECT_EQ(batches, 4);
}

TEST(UpdatePolicy, IncrementalModeNeverBatchesAfterTheFirst) {
  const UpdatePolicy p = policy({{"mode", "incremental"}});
  for (long step = 1; step <= 100; ++step) {
    EXPECT_FALSE(p.decide(step, 1000, 1e6, costs(1e9, 1, 100)).batch);
  }
}

TEST(UpdatePolicy, RejectsBadOptions) {
  EXPECT_THROW(policy({{"mode", "sometimes"}}), Error);
  EXPECT_THROW(policy({{"cost", "cpu"}}), Error);
  EXPECT_THROW(policy({{"period", "0"}}), Error);
  EXPECT_THROW(policy({{"period", "x"}}), Error);
  EXPECT_THROW(policy({{"delta_t", "-1"}}), Error);
  EXPECT_THROW(policy({{"delta_t", "nan"}}), Error);
  EXPECT_THROW(policy({{"nl_t", "0"}}), Error);
  EXPECT_THROW(policy({{"big_delta_t", "0"}}), Error);
  EXPECT_THROW(policy({{"nl_tt", "5"}}), Error);
  try {
    policy({{"period", "-3"}});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "aprilsam: option period=-3 must be >= 1");
  }
  UpdatePolicyOptions bad;
  bad.nl_t = -1;
  EXPECT_THROW(UpdatePolicy{bad}, Error);
  EXPECT_EQ(policy({{"cost", "wallclock"}}).options().cost, UpdatePolicyOptions::Cost::kWallclock);
  EXPECT_EQ(policy({{"mode", "periodic"}}).options().mode, UpdatePolicyOptions::Mode::kPeriodic);
  EXPECT_STREQ(toString(UpdatePolicyOptions::Mode::kIncremental), "incremental");
}

TEST(FactorizationCost, FlopsAreTheSumOfSquaredColumnCounts) {
  EXPECT_DOUBLE_EQ(choleskyFlops({}), 0.0);
  EXPECT_DOUBLE_EQ(choleskyFlops({1, 2, 3}), 14.0);
  // A dense n x n factor: sum_k k^2.
  EXPECT_DOUBLE_EQ(choleskyFlops(choleskyColumnCounts({{1, 2}, {0, 2}, {0, 1}}, {0, 1, 2})),
                   9.0 + 4.0 + 1.0);
}

}  // namespace
}  // namespace hamal::aprilsam
