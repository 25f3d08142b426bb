// GtsamFactorAdapter: see gtsam_factor_adapter.h.
#include "gtsam_factor_adapter.h"

#include <gtsam/geometry/Point2.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/geometry/Rot2.h>
#include <gtsam/linear/NoiseModel.h>
#include <gtsam/linear/linearExceptions.h>
#include <gtsam/nonlinear/NonlinearFactor.h>
#include <gtsam/sam/BearingRangeFactor.h>
#include <gtsam/slam/BetweenFactor.h>
#include <gtsam/slam/PriorFactor.h>

#include <Eigen/Core>
#include <exception>
#include <typeinfo>
#include <unordered_set>

#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace hamal::gtsam_plugin {

namespace {

// diag(R(angle)^T, 1) Omega diag(R(angle), 1): the information of an error
// whose translation part is the other one's rotated by R(angle)^T.
Eigen::Matrix3d rotatedInformation(const Eigen::Matrix3d& information, double angle) {
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  const double c = std::cos(angle), s = std::sin(angle);
  d(0, 0) = c;  // R(angle)^T = [c s; -s c]
  d(0, 1) = s;
  d(1, 0) = -s;
  d(1, 1) = c;
  return d * information * d.transpose();
}

gtsam::SharedNoiseModel informationModel(const gtsam::Matrix& information) {
  // smart = true: a diagonal information gives GTSAM's cheaper diagonal model.
  return gtsam::noiseModel::Gaussian::Information(information, true);
}

// hamal's pose prior, e = [t - t0, wrap(th - th0)] (factors/prior_factor.h).
// GTSAM's PriorFactor<Pose2> error, -Local(x, p0), has its translation in the
// frame of the current heading th, which no constant information matrix
// maps to hamal's world-frame one; so the prior is written here. GTSAM's
// Pose2 retract moves x by x * Pose2(v), so de/dv = diag(R(th), 1).
class ThesisPosePrior : public gtsam::NoiseModelFactorN<gtsam::Pose2> {
 public:
  ThesisPosePrior(gtsam::Key key, const gtsam::Pose2& prior, const gtsam::SharedNoiseModel& model)
      : gtsam::NoiseModelFactorN<gtsam::Pose2>(model, key), prior_(prior) {}

  gtsam::Vector evaluateError(const gtsam::Pose2& x, gtsam::OptionalMatrixType H) const override {
    if (H) {
      gtsam::Matrix3 j = gtsam::Matrix3::Identity();
      j.topLeftCorner<2, 2>() = x.rotation().matrix();
      *H = j;
    }
    return gtsam::Vector3(x.x() - prior_.x(), x.y() - prior_.y(),
                          gtsam::Rot2::fromAngle(x.theta() - prior_.theta()).theta());
  }

  gtsam::NonlinearFactor::shared_ptr clone() const override {
    return gtsam::NonlinearFactor::shared_ptr(new ThesisPosePrior(*this));
  }

 private:
  gtsam::Pose2 prior_;
};

std::string describe(const Factor& factor) {
  std::string keys;
  for (Key k : factor.keys()) keys += (keys.empty() ? "" : " ") + k.str();
  return factor.tag() + " on " + keys;
}

}  // namespace

gtsam::NonlinearFactor::shared_ptr toGtsamFactor(const Factor& factor, const std::string& backend) {
  if (factor.lossFunction())
    throw Error(backend + ": factor " + describe(factor) +
                " has a robust loss, which the GTSAM adapter does not map (it maps between, "
                "prior, range-bearing and landmark-prior factors without a loss)");
  const auto& keys = factor.keys();
  // Exact types: a subclass (a plugin's between with its own tag) may mean
  // something else, so it is refused rather than guessed.
  const std::type_info& type = typeid(factor);
  if (type == typeid(BetweenFactor)) {
    const auto& f = static_cast<const BetweenFactor&>(factor);
    const Pose2& z = f.measurement();
    const Eigen::Matrix3d information = f.residual() == BetweenResidual::kMeasurementFrame
                                            ? f.information()
                                            : rotatedInformation(f.information(), z.theta);
    return gtsam::NonlinearFactor::shared_ptr(new gtsam::BetweenFactor<gtsam::Pose2>(
        toGtsam(keys[0]), toGtsam(keys[1]), gtsam::Pose2(z.x, z.y, z.theta),
        informationModel(information)));
  }
  if (type == typeid(PriorFactor)) {
    const auto& f = static_cast<const PriorFactor&>(factor);
    const Pose2& p = f.measurement();
    return gtsam::NonlinearFactor::shared_ptr(new ThesisPosePrior(
        toGtsam(keys[0]), gtsam::Pose2(p.x, p.y, p.theta), informationModel(f.information())));
  }
  if (type == typeid(RangeBearingFactor)) {
    const auto& f = static_cast<const RangeBearingFactor&>(factor);
    Eigen::Matrix2d swapped;  // (bearing, range)
    swapped << f.information()(1, 1), f.information()(1, 0), f.information()(0, 1),
        f.information()(0, 0);
    return gtsam::NonlinearFactor::shared_ptr(
        new gtsam::BearingRangeFactor<gtsam::Pose2, gtsam::Point2>(
            toGtsam(keys[0]), toGtsam(keys[1]), gtsam::Rot2::fromAngle(f.bearing()), f.range(),
            informationModel(swapped)));
  }
  if (type == typeid(LandmarkPriorFactor)) {
    const auto& f = static_cast<const LandmarkPriorFactor&>(factor);
    return gtsam::NonlinearFactor::shared_ptr(new gtsam::PriorFactor<gtsam::Point2>(
        toGtsam(keys[0]), gtsam::Point2(f.measurement()), informationModel(f.information())));
  }
  throw Error(backend + ": factor " + describe(factor) +
              " has no GTSAM counterpart in the adapter (it maps EDGE_SE2/EDGE2 between, "
              "EDGE_SE2_PRIOR, EDGE_SE2_RANGE_BEARING and EDGE_XY_PRIOR factors)");
}

gtsam::NonlinearFactorGraph toGtsamFactors(const std::vector<FactorPtr>& factors,
                                           const std::string& backend) {
  gtsam::NonlinearFactorGraph out;
  out.reserve(factors.size());
  for (const auto& f : factors) out.push_back(toGtsamFactor(*f, backend));
  return out;
}

void insertGtsamValue(Key key, const Values::Entry& entry, gtsam::Values* out) {
  const auto& d = entry.data;
  if (entry.type == VariableType::kPose2)
    out->insert(toGtsam(key), gtsam::Pose2(d[0], d[1], d[2]));
  else
    out->insert(toGtsam(key), gtsam::Point2(d[0], d[1]));
}

gtsam::NonlinearFactor::shared_ptr fixedPrior(Key key, const Values::Entry& entry) {
  const auto& d = entry.data;
  if (entry.type == VariableType::kPose2)
    return gtsam::NonlinearFactor::shared_ptr(
        new gtsam::PriorFactor<gtsam::Pose2>(toGtsam(key), gtsam::Pose2(d[0], d[1], d[2]),
                                             gtsam::noiseModel::Isotropic::Sigma(3, kFixedSigma)));
  return gtsam::NonlinearFactor::shared_ptr(
      new gtsam::PriorFactor<gtsam::Point2>(toGtsam(key), gtsam::Point2(d[0], d[1]),
                                            gtsam::noiseModel::Isotropic::Sigma(2, kFixedSigma)));
}

std::vector<Key> addFixedPriors(const Step& step, const Values& estimate,
                                const std::unordered_set<Key>& already,
                                gtsam::NonlinearFactorGraph* factors) {
  std::vector<Key> added;
  for (Key k : step.fixed) {
    if (already.count(k)) continue;
    const Values::Entry& at =
        step.new_values.contains(k) ? step.new_values.entry(k) : estimate.entry(k);
    factors->push_back(fixedPrior(k, at));
    added.push_back(k);
  }
  return added;
}

void copyFromGtsam(const gtsam::Values& from, const std::vector<Key>& keep, Values* estimate) {
  const std::unordered_set<Key> kept(keep.begin(), keep.end());
  for (const auto& kv : from) {
    const Key key = fromGtsam(kv.key);
    if (kept.count(key) || !estimate->contains(key)) continue;
    const VariableType type = estimate->type(key);
    try {
      if (type == VariableType::kPose2) {
        const auto& p = kv.value.cast<gtsam::Pose2>();
        estimate->set(key, Pose2(p.x(), p.y(), p.theta()));
      } else {
        const auto& p = kv.value.cast<gtsam::Point2>();
        estimate->set(key, Point2(p.x(), p.y()));
      }
    } catch (const std::exception& e) {
      throw Error("GTSAM's value of " + key.str() + " is not a " + typeName(type) + ": " +
                  e.what());
    }
  }
}

Status gtsamFailure(const std::string& backend) {
  try {
    throw;
  } catch (const gtsam::IndeterminantLinearSystemException& e) {
    const Key near = fromGtsam(e.nearbyVariable());
    return Status::numericalFailure(backend +
                                        ": GTSAM found the linear system indeterminant near "
                                        "variable " +
                                        near.str() + " (is the graph anchored by a prior?)",
                                    {near});
  } catch (const std::exception& e) {
    return Status::numericalFailure(backend + ": GTSAM: " + e.what());
  }
}

}  // namespace hamal::gtsam_plugin
