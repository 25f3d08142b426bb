// Key, Pose2 and Values: typed keys, rigid-body algebra, stable storage.
#include "core/values.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "core/error.h"
#include "core/key.h"
#include "core/pose2.h"

namespace hamal {
namespace {

TEST(Key, KindAndIndexAreSeparate) {
  EXPECT_NE(X(5), L(5));
  EXPECT_EQ(X(5).kind(), 'x');
  EXPECT_EQ(L(5).index(), 5u);
  EXPECT_EQ(X(12).str(), "x12");
  EXPECT_LT(X(1), X(2));
  EXPECT_EQ(Key('q', Key::kMaxIndex).index(), Key::kMaxIndex);
}

TEST(Pose2, WrapAngleIsHalfOpen) {
  const double pi = M_PI;
  EXPECT_NEAR(wrapAngle(pi), pi, 1e-15);
  EXPECT_NEAR(wrapAngle(-pi), pi, 1e-15);
  EXPECT_NEAR(wrapAngle(3 * pi + 0.1), -pi + 0.1, 1e-12);
  EXPECT_NEAR(wrapAngle(-0.3), -0.3, 1e-15);
}

// The in-range shortcut gives fmod's result to the bit, at the ends of the
// range, beyond it and for non-finite angles.
TEST(Pose2, WrapAngleEqualsFmodBitForBit) {
  const auto by_fmod = [](double a) {
    constexpr double kPi = 3.14159265358979323846;
    a = std::fmod(a + kPi, 2.0 * kPi);
    if (a <= 0.0) a += 2.0 * kPi;
    return a - kPi;
  };
  std::vector<double> angles = {0.0,
                                -0.0,
                                M_PI,
                                -M_PI,
                                std::nextafter(M_PI, 0.0),
                                std::nextafter(-M_PI, 0.0),
                                std::nextafter(M_PI, 4.0),
                                std::nextafter(-M_PI, -4.0),
                                2 * M_PI,
                                -2 * M_PI,
                                1e300,
                                -1e300,
                                5e-324,
                                HUGE_VAL,
                                -HUGE_VAL,
                                std::nan("")};
  std::mt19937 rng(7);
  for (double scale : {1e-12, 1e-3, 1.0, M_PI, 4.0, 10.0, 1e3, 1e9}) {
    std::uniform_real_distribution<double> u(-scale, scale);
    for (int i = 0; i < 2000; ++i) angles.push_back(u(rng));
  }
  for (double a : angles) {
    const double got = wrapAngle(a), want = by_fmod(a);
    EXPECT_EQ(std::memcmp(&got, &want, sizeof got), 0) << a << ": " << got << " vs " << want;
  }
}

TEST(Pose2, ComposeBetweenInverse) {
  const Pose2 a(1, 2, 0.3), b(-4, 0.5, -2.9);
  const Pose2 ab = a.between(b);
  const Pose2 b2 = a.compose(ab);
  EXPECT_NEAR(b2.x, b.x, 1e-12);
  EXPECT_NEAR(b2.y, b.y, 1e-12);
  EXPECT_NEAR(wrapAngle(b2.theta - b.theta), 0, 1e-12);
  const Pose2 id = a.compose(a.inverse());
  EXPECT_NEAR(id.x, 0, 1e-12);
  EXPECT_NEAR(id.y, 0, 1e-12);
  EXPECT_NEAR(id.theta, 0, 1e-12);
  const Point2 p(3, -1);
  EXPECT_TRUE(a.transformTo(a.transformFrom(p)).isApprox(p, 1e-12));
}

TEST(Values, TypedAccessAndErrors) {
  Values v;
  v.insert(X(0), Pose2(1, 2, 3));
  v.insert(L(0), Point2(4, 5));
  EXPECT_EQ(v.dim(X(0)), 3);
  EXPECT_EQ(v.dim(L(0)), 2);
  EXPECT_EQ(v.pose(X(0)).y, 2);
  EXPECT_THROW(v.point(X(0)), Error);
  EXPECT_THROW(v.pose(X(7)), Error);
  EXPECT_THROW(v.insert(X(0), Pose2()), Error);
  EXPECT_EQ(v.keys(), (std::vector<Key>{L(0), X(0)}));
}

TEST(Values, RetractWrapsAnglesAndPointersStayValid) {
  Values v;
  v.insert(X(0), Pose2(0, 0, 3.0));
  double* p = v.data(X(0));
  for (int i = 1; i < 1000; ++i) v.insert(X(i), Pose2());  // forces rehashing
  EXPECT_EQ(p, v.data(X(0)));
  const double d[3] = {1, 2, 0.5};
  v.retract(X(0), d);
  EXPECT_NEAR(v.pose(X(0)).theta, 3.5 - 2 * M_PI, 1e-12);
  EXPECT_EQ(v.pose(X(0)).x, 1);
}

}  // namespace
}  // namespace hamal
