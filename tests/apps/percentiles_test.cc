// Percentile math of the benchmark summaries (apps/bench/percentiles.h):
// linear interpolation between closest ranks, as numpy.percentile.
#include "apps/bench/percentiles.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace hamal::apps {
namespace {

TEST(Percentile, InterpolatesBetweenClosestRanks) {
  const std::vector<double> x = {4, 1, 3, 2};  // unsorted on purpose
  EXPECT_DOUBLE_EQ(percentile(x, 0), 1.0);
  EXPECT_DOUBLE_EQ(percentile(x, 50), 2.5);    // mean of the middle two
  EXPECT_NEAR(percentile(x, 90), 3.7, 1e-12);  // numpy.percentile([1,2,3,4], 90)
  EXPECT_NEAR(percentile(x, 99), 3.97, 1e-12);
  EXPECT_DOUBLE_EQ(percentile(x, 100), 4.0);
  EXPECT_DOUBLE_EQ(median({5, 1, 9}), 5.0);
}

TEST(Percentile, HundredSamples) {
  std::vector<double> x;
  for (int i = 1; i <= 100; ++i) x.push_back(i);
  EXPECT_DOUBLE_EQ(percentile(x, 50), 50.5);
  EXPECT_NEAR(percentile(x, 99), 99.01, 1e-12);
  EXPECT_NEAR(percentile(x, 90), 90.1, 1e-12);
}

TEST(Percentile, EdgeCases) {
  EXPECT_TRUE(std::isnan(percentile({}, 50)));
  EXPECT_DOUBLE_EQ(percentile({7}, 99), 7.0);
  EXPECT_THROW(percentile({1, 2}, 101), Error);
  EXPECT_THROW(percentile({1, 2}, -1), Error);
}

TEST(ShareBelow, CountsStrictlySmaller) {
  EXPECT_DOUBLE_EQ(shareBelow({0.001, 0.009, 0.010, 0.2}, 0.010), 0.5);
  EXPECT_DOUBLE_EQ(shareBelow({}, 1), 0.0);
}

}  // namespace
}  // namespace hamal::apps
