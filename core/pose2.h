// Pose2 and Point2: the two variable types of a 2D pose/feature graph
// (thesis sec. 2.2.1, eq. 2.27: a pose is (x, y, theta), a rigid transform
// from the robot's frame to the global frame).
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace hamal {

// Wraps an angle to (-pi, pi], the convention of the chi2 (docs/PROTOCOL.md).
inline double wrapAngle(double a) {
  constexpr double kPi = 3.14159265358979323846;
  // fmod is exact and returns x itself for 0 <= x < y, so an angle already
  // in range skips it with the same result to the bit; fmod's call costs
  // more than the rest of a between factor's residual.
  const double b = a + kPi;
  if (b > 0.0 && b < 2.0 * kPi) return b - kPi;
  a = std::fmod(b, 2.0 * kPi);
  if (a <= 0.0) a += 2.0 * kPi;
  return a - kPi;
}

using Point2 = Eigen::Vector2d;

struct Pose2 {
  double x = 0.0, y = 0.0, theta = 0.0;

  Pose2() = default;
  Pose2(double x_, double y_, double theta_) : x(x_), y(y_), theta(theta_) {}

  Eigen::Vector2d t() const { return {x, y}; }
  Eigen::Matrix2d R() const {
    const double c = std::cos(theta), s = std::sin(theta);
    Eigen::Matrix2d r;
    r << c, -s, s, c;
    return r;
  }

  // this * other: other is expressed in this pose's frame (T_ga * T_ab).
  Pose2 compose(const Pose2& o) const {
    const Eigen::Vector2d p = t() + R() * o.t();
    return {p.x(), p.y(), wrapAngle(theta + o.theta)};
  }
  Pose2 inverse() const {
    const Eigen::Vector2d p = -(R().transpose() * t());
    return {p.x(), p.y(), wrapAngle(-theta)};
  }
  // this^-1 * other: other as seen from this pose (eq. 2.28-2.30).
  Pose2 between(const Pose2& o) const {
    const Eigen::Vector2d p = R().transpose() * (o.t() - t());
    return {p.x(), p.y(), wrapAngle(o.theta - theta)};
  }
  // A point in this pose's frame, expressed in the global frame.
  Point2 transformFrom(const Point2& p) const { return t() + R() * p; }
  // A global point, expressed in this pose's frame.
  Point2 transformTo(const Point2& p) const { return R().transpose() * (p - t()); }
};

}  // namespace hamal
