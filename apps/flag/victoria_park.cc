// Victoria Park as a FLAG recording with a labelled map (victoria_park.h).
#include "apps/flag/victoria_park.h"

#include <Eigen/LU>
#include <cmath>
#include <map>
#include <random>

#include "apps/bench/bench_runner.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/stopwatch.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::flag {

VictoriaPark prepareVictoriaPark(const std::string& path, const Registry& registry,
                                 const std::string& backend, double label_sigma,
                                 std::uint64_t seed) {
  if (!(label_sigma >= 0) || !std::isfinite(label_sigma))
    throw Error("label sigma must be >= 0 and finite");
  const Graph graph = readGraph(path, registry, Format::kGtsam);
  VictoriaPark vp;

  // The known-association solution: the thesis protocol on `backend`.
  const Stopwatch watch;
  const ThesisProtocol protocol(graph);
  std::unique_ptr<Backend> solver = registry.makeBackend(backend);
  apps::RunOptions options;
  options.score = false;
  const apps::RunOutcome outcome =
      apps::summarizeRows(apps::runThesisProtocol(protocol, *solver, backend, options).rows);
  if (!outcome.status.ok())
    throw Error(path + ": the known-association solution failed at " + outcome.describe());
  vp.reference_seconds = watch.seconds();
  const Values& ref = solver->estimate();

  // Poses in the protocol's order; odometry and detections per pose.
  std::map<Key, std::size_t> index;
  for (std::size_t i = 0; i < protocol.size(); ++i) index[protocol.pose(i)] = i;
  vp.recording.steps.resize(protocol.size());
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    vp.recording.steps[i].truth = ref.pose(protocol.pose(i));
    vp.recording.steps[i].time = double(i);
  }
  std::vector<bool> has_odometry(protocol.size(), false);
  for (const FactorPtr& f : graph.factors) {
    if (const auto* b = dynamic_cast<const BetweenFactor*>(f.get())) {
      const std::size_t a = index.at(b->keys()[0]), c = index.at(b->keys()[1]);
      Pose2 z = b->measurement();
      std::size_t later = c;
      if (c + 1 == a) {
        z = z.inverse();
        later = a;
      } else if (a + 1 != c) {
        throw Error(path + ": odometry between " + b->keys()[0].str() + " and " +
                    b->keys()[1].str() + " does not join consecutive poses");
      }
      RecordedStep& s = vp.recording.steps[later];
      s.odometry = z;
      s.distance = std::hypot(z.x, z.y);
      const Eigen::Matrix3d cov = b->information().inverse();
      s.odometry_sigma = cov.diagonal().cwiseSqrt();
      has_odometry[later] = true;
    } else if (const auto* p = dynamic_cast<const PosePointFactor*>(f.get())) {
      RecordedStep& s = vp.recording.steps[index.at(p->keys()[0])];
      const Point2 z = p->measurement();
      const Eigen::Matrix2d cov = p->information().inverse();
      const double sigma = std::sqrt(std::max(cov(0, 0), cov(1, 1)));
      Detection d;
      d.range = z.norm();
      d.bearing = std::atan2(z.y(), z.x());
      d.range_sigma = sigma;
      d.bearing_sigma = sigma / std::max(d.range, 0.5);
      d.source = {Source::kCorner, p->keys()[1].index()};
      s.detections.push_back(d);
    }
  }
  for (std::size_t i = 1; i < has_odometry.size(); ++i)
    if (!has_odometry[i])
      throw Error(path + ": pose " + protocol.pose(i).str() + " has no odometry");

  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (const Key key : ref.keys()) {
    if (key.kind() != kLandmarkKind) continue;
    const Point2 tree = ref.point(key);
    vp.reference_landmarks.insert(key, tree);
    const double ex = n01(rng), ey = n01(rng);
    vp.labels.push_back({key.index(), tree + label_sigma * Point2(ex, ey), {}});
  }
  return vp;
}

}  // namespace hamal::flag
