// Metrics: see metrics.h.
#include "core/metrics.h"

#include <cmath>

#include "core/error.h"

namespace hamal {

double chi2(const std::vector<FactorPtr>& factors, const Values& values) {
  double total = 0.0;
  for (const auto& f : factors) {
    for (Key k : f->keys())
      if (!values.contains(k)) throw Error("chi2: variable " + k.str() + " has no value");
    total += f->chi2(values);
  }
  return total;
}

double robustChi2(const Factor& factor, const Values& values) {
  const double s = factor.chi2(values);
  const ceres::LossFunction* loss = factor.lossFunction();
  if (!loss || !std::isfinite(s)) return s;
  double rho[3];
  loss->Evaluate(s, rho);
  return rho[0];
}

double robustCost(const std::vector<FactorPtr>& factors, const Values& values) {
  double total = 0.0;
  for (const auto& f : factors) {
    for (Key k : f->keys())
      if (!values.contains(k)) throw Error("robustCost: variable " + k.str() + " has no value");
    total += robustChi2(*f, values);
  }
  return total;
}

TrajectoryError absoluteTrajectoryError(const Values& estimate, const Values& truth, bool align) {
  std::vector<Pose2> a, b;  // estimate, truth
  for (const auto& [key, entry] : truth) {
    if (entry.type != VariableType::kPose2 || !estimate.contains(key)) continue;
    if (estimate.type(key) != VariableType::kPose2) continue;
    a.push_back(estimate.pose(key));
    b.push_back(truth.pose(key));
  }
  TrajectoryError out;
  out.poses = a.size();
  if (a.empty()) return out;
  Pose2 fit;  // maps estimate into the truth's frame
  if (align) {
    Eigen::Vector2d ma = Eigen::Vector2d::Zero(), mb = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < a.size(); ++i) ma += a[i].t(), mb += b[i].t();
    ma /= double(a.size());
    mb /= double(a.size());
    double sxx = 0, sxy = 0;  // sum of cross terms: angle of the best rotation
    for (std::size_t i = 0; i < a.size(); ++i) {
      const Eigen::Vector2d p = a[i].t() - ma, q = b[i].t() - mb;
      sxx += p.dot(q);
      sxy += p.x() * q.y() - p.y() * q.x();
    }
    const double th = std::atan2(sxy, sxx);
    const Eigen::Vector2d t = mb - Pose2(0, 0, th).R() * ma;
    fit = Pose2(t.x(), t.y(), th);
  }
  double st = 0, sr = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Pose2 e = fit.compose(a[i]);
    st += (e.t() - b[i].t()).squaredNorm();
    const double dr = wrapAngle(e.theta - b[i].theta);
    sr += dr * dr;
  }
  out.translation_rmse = std::sqrt(st / double(a.size()));
  out.rotation_rmse = std::sqrt(sr / double(a.size()));
  return out;
}

}  // namespace hamal
