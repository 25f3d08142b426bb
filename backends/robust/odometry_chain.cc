// OdometryChain: prefix sums of composed odometry (odometry_chain.h).
#include "backends/robust/odometry_chain.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <string>

#include "core/error.h"

namespace hamal::robust {
namespace {

Eigen::Matrix3d rotationBlock(double theta) {
  Eigen::Matrix3d g = Eigen::Matrix3d::Identity();
  g.topLeftCorner<2, 2>() = Pose2(0, 0, theta).R();
  return g;
}

std::string poseName(std::uint64_t id) { return X(id).str(); }

}  // namespace

// d(-R^T t) = -R^T dt + J R^T t dtheta, d(-theta) = -dtheta.
UncertainPose inverse(const UncertainPose& z) {
  UncertainPose out;
  out.pose = z.pose.inverse();
  Eigen::Matrix3d jac = Eigen::Matrix3d::Zero();
  const Eigen::Matrix2d rt = z.pose.R().transpose();
  jac.topLeftCorner<2, 2>() = -rt;
  const Eigen::Vector2d rtt = rt * z.pose.t();
  jac(0, 2) = -rtt.y();
  jac(1, 2) = rtt.x();
  jac(2, 2) = -1;
  out.covariance = jac * z.covariance * jac.transpose();
  return out;
}

Eigen::Matrix3d adjoint(const Pose2& x) {
  Eigen::Matrix3d ad = rotationBlock(x.theta);
  ad(0, 2) = x.y;
  ad(1, 2) = -x.x;
  return ad;
}

Eigen::Matrix3d additiveFromLeft(const Eigen::Vector2d& t) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  a(0, 2) = -t.y();
  a(1, 2) = t.x();
  return a;
}

bool OdometryChain::isOdometry(const Factor& factor) {
  const auto& keys = factor.keys();
  if (keys.size() != 2 || keys[0].kind() != kPoseKind || keys[1].kind() != kPoseKind) return false;
  const auto a = keys[0].index(), b = keys[1].index();
  if ((a > b ? a - b : b - a) != 1) return false;
  return relativePoseOf(factor).has_value();
}

void OdometryChain::add(const Factor& factor) {
  if (!isOdometry(factor)) {
    std::string keys;
    for (Key k : factor.keys()) keys += " " + k.str();
    throw Error("odometry chain: factor " + factor.tag() + keys +
                " is not odometry (two poses one id apart with a relative-pose measurement)");
  }
  add(*relativePoseOf(factor));
}

void OdometryChain::add(const RelativePose& link) {
  const std::uint64_t a = link.from.index(), b = link.to.index();
  if (link.from.kind() != kPoseKind || link.to.kind() != kPoseKind || (a + 1 != b && b + 1 != a))
    throw Error("odometry chain: " + link.from.str() + " -> " + link.to.str() +
                " does not join consecutive poses");
  Eigen::LDLT<Eigen::Matrix3d> ldlt(link.information);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !link.information.allFinite())
    throw Error("odometry chain: the information of " + link.from.str() + " -> " + link.to.str() +
                " is not positive definite");
  UncertainPose z{link.measurement, link.information.inverse()};
  if (b + 1 == a) z = inverse(z);
  const std::uint64_t key = std::min(a, b);
  auto it = links_.find(key);
  if (it != links_.end()) {
    // Two measurements of one link: the information-weighted mean, in the
    // additive coordinates of the first.
    const Eigen::Matrix3d w1 = it->second.covariance.inverse(), w2 = z.covariance.inverse();
    const Eigen::Matrix3d cov = (w1 + w2).inverse();
    const Eigen::Vector3d d(z.pose.x - it->second.pose.x, z.pose.y - it->second.pose.y,
                            wrapAngle(z.pose.theta - it->second.pose.theta));
    const Eigen::Vector3d step = cov * w2 * d;
    it->second.pose = Pose2(it->second.pose.x + step.x(), it->second.pose.y + step.y(),
                            wrapAngle(it->second.pose.theta + step.z()));
    it->second.covariance = cov;
    dirty_ = true;
    return;
  }
  links_.emplace(key, z);
  if (!dirty_ && !pose_.empty() && key == first_ + pose_.size() - 1) {
    append(key + 1);
    return;
  }
  dirty_ = true;
}

void OdometryChain::append(std::uint64_t id) const {
  const auto it = links_.find(id - 1);
  if (it == links_.end()) {  // a missing link starts a new segment
    pose_.emplace_back();
    qbar_.push_back(qbar_.back());
    segment_.push_back(segment_.back() + 1);
    return;
  }
  const Pose2& prev = pose_.back();
  const Pose2 next = prev.compose(it->second.pose);
  const Eigen::Matrix3d k = additiveFromLeft(-next.t()) * rotationBlock(prev.theta);
  pose_.push_back(next);
  qbar_.push_back(qbar_.back() + k * it->second.covariance * k.transpose());
  segment_.push_back(segment_.back());
}

void OdometryChain::rebuild() const {
  dirty_ = false;
  pose_.clear();
  qbar_.clear();
  segment_.clear();
  if (links_.empty()) return;
  first_ = links_.begin()->first;
  const std::uint64_t last = links_.rbegin()->first + 1;
  pose_.reserve(last - first_ + 1);
  qbar_.reserve(last - first_ + 1);
  segment_.reserve(last - first_ + 1);
  pose_.emplace_back();
  qbar_.push_back(Eigen::Matrix3d::Zero());
  segment_.push_back(0);
  for (std::uint64_t id = first_ + 1; id <= last; ++id) append(id);
}

std::size_t OdometryChain::index(std::uint64_t id) const {
  if (dirty_) rebuild();
  if (pose_.empty() || id < first_ || id - first_ >= pose_.size())
    throw Error("odometry chain: pose " + poseName(id) + " has no odometry link");
  return static_cast<std::size_t>(id - first_);
}

void OdometryChain::requireJoined(std::uint64_t a, std::uint64_t b) const {
  const std::size_t ia = index(a), ib = index(b);
  if (segment_[ia] == segment_[ib]) return;
  const std::size_t lo = std::min(ia, ib);
  std::size_t m = lo + 1;
  while (segment_[m] == segment_[lo]) ++m;
  throw Error("odometry chain: no odometry between " + poseName(a) + " and " + poseName(b) +
              ": the link " + poseName(first_ + m - 1) + " -> " + poseName(first_ + m) +
              " is missing");
}

bool OdometryChain::joined(std::uint64_t a, std::uint64_t b) const {
  if (dirty_) rebuild();
  const auto inside = [this](std::uint64_t id) {
    return !pose_.empty() && id >= first_ && id - first_ < pose_.size();
  };
  if (!inside(a) || !inside(b)) return false;
  return segment_[static_cast<std::size_t>(a - first_)] ==
         segment_[static_cast<std::size_t>(b - first_)];
}

const Pose2& OdometryChain::pose(std::uint64_t id) const { return pose_[index(id)]; }

Eigen::Matrix3d OdometryChain::noiseCovariance(std::uint64_t a, std::uint64_t b) const {
  requireJoined(a, b);
  const std::size_t ia = index(a), ib = index(b);
  return ia < ib ? Eigen::Matrix3d(qbar_[ib] - qbar_[ia]) : Eigen::Matrix3d(qbar_[ia] - qbar_[ib]);
}

Eigen::Matrix3d OdometryChain::noiseCrossCovariance(std::uint64_t a, std::uint64_t b,
                                                    std::uint64_t c, std::uint64_t d) const {
  requireJoined(a, b);
  requireJoined(c, d);
  const std::size_t ia = index(a), ib = index(b), ic = index(c), id = index(d);
  const std::size_t lo = std::max(std::min(ia, ib), std::min(ic, id));
  const std::size_t hi = std::min(std::max(ia, ib), std::max(ic, id));
  if (hi <= lo) return Eigen::Matrix3d::Zero();
  const double sign = ((ib > ia) == (id > ic)) ? 1.0 : -1.0;
  return sign * (qbar_[hi] - qbar_[lo]);
}

UncertainPose OdometryChain::between(std::uint64_t a, std::uint64_t b) const {
  requireJoined(a, b);
  const Pose2& pa = pose(a);
  UncertainPose out;
  out.pose = pa.between(pose(b));
  const Eigen::Matrix3d m = additiveFromLeft(out.pose.t()) * adjoint(pa.inverse());
  out.covariance = m * noiseCovariance(a, b) * m.transpose();
  return out;
}

}  // namespace hamal::robust
