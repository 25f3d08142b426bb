// hamal_gtsam_marginals: GTSAM's Marginals on a 2D pose graph at values hamal
// wrote, with no hamal code between GTSAM and its answer: the reference and
// the cost that hamal's marginal covariances (core/marginals.h) are compared
// against (python/benchmarks/marginals_cost.py --gtsam).
//
//   hamal_gtsam_marginals --data GRAPH --values VALUES [--repeat N]
//
// GRAPH: a pose graph hamal reads (g2o or TORO), its between edges only, each
// a GTSAM BetweenFactor<Pose2> with the file's information (GTSAM's residual
// is hamal's `--residual measurement`). The gauge is the thesis protocol's
// prior on its first pose (protocol/thesis_protocol.h), taken from hamal's
// protocol, as a PriorFactor<Pose2> whose information is turned into the
// prior's frame (GTSAM's prior error is there, hamal's in the world frame).
// VALUES: a g2o file of VERTEX_SE2 lines (hamal writes 17 digits) holding
// every pose: the point both linearise at. Any other factor or variable is an
// error naming it.
//
// Times are medians of --repeat runs: "construct" is Marginals(graph, values)
// (linearisation and a multifrontal Cholesky elimination), "query" is
// marginalCovariance(last pose) on it. Printed as one JSON object, with the
// last pose's 3x3 covariance in GTSAM's body-frame tangent and in hamal's
// (world-frame x, y: T Sigma T^T, T = diag(R(theta), 1)), 17 digits.
#include <gflags/gflags.h>
#include <gtsam/config.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/nonlinear/Marginals.h>
#include <gtsam/nonlinear/NonlinearFactorGraph.h>
#include <gtsam/nonlinear/Values.h>
#include <gtsam/slam/BetweenFactor.h>
#include <gtsam/slam/PriorFactor.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <typeinfo>
#include <vector>

#include "apps/common/cli.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"
#include "factors/register_factors.h"
#include "protocol/thesis_protocol.h"

DEFINE_string(data, "", "the pose graph, g2o or TORO");
DEFINE_string(values, "", "the linearisation point: a g2o file of VERTEX_SE2 lines, every pose");
DEFINE_int32(repeat, 3, "runs of Marginals construction and the query; times are medians");

namespace {

using hamal::Error;
using hamal::Key;

gtsam::Key gtsamKey(Key key, const std::string& where) {
  if (key.kind() != 'x') throw Error(where + ": " + key.str() + " is not a pose");
  return key.index();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void printMatrix(const char* name, const gtsam::Matrix& m) {
  std::printf("  \"%s\": [", name);
  for (int r = 0; r < m.rows(); ++r) {
    std::printf("%s[", r ? ", " : "");
    for (int c = 0; c < m.cols(); ++c) std::printf("%s%.17g", c ? ", " : "", m(r, c));
    std::printf("]");
  }
  std::printf("],\n");
}

}  // namespace

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_gtsam_marginals", [&] {
    hamal::apps::parseCommandLine(
        &argc, &argv,
        "GTSAM's Marginals of a pose graph's last pose at values hamal wrote.\n\n"
        "  hamal_gtsam_marginals --data GRAPH --values VALUES [--repeat N]");
    if (FLAGS_data.empty() || FLAGS_values.empty())
      throw Error("give --data GRAPH and --values VALUES (see --help)");
    if (FLAGS_repeat < 1) throw Error("--repeat must be at least 1");
    hamal::Registry registry;
    hamal::registerFactors(registry);
    const hamal::Graph graph = hamal::readGraph(FLAGS_data, registry);
    const hamal::Graph point = hamal::readGraph(FLAGS_values, registry);
    const hamal::ThesisProtocol protocol(graph);

    gtsam::NonlinearFactorGraph factors;
    for (const hamal::FactorPtr& f : graph.factors) {
      const auto* between = dynamic_cast<const hamal::BetweenFactor*>(f.get());
      if (!between || typeid(*f) != typeid(hamal::BetweenFactor))
        throw Error(FLAGS_data + ": factor " + f->tag() + " is not a between edge");
      const hamal::Pose2& z = between->measurement();
      factors.emplace_shared<gtsam::BetweenFactor<gtsam::Pose2>>(
          gtsamKey(f->keys()[0], FLAGS_data), gtsamKey(f->keys()[1], FLAGS_data),
          gtsam::Pose2(z.x, z.y, z.theta),
          gtsam::noiseModel::Gaussian::Information(between->information()));
    }
    const auto* prior = dynamic_cast<const hamal::PriorFactor*>(protocol.prior().get());
    if (!prior) throw Error(FLAGS_data + ": the thesis protocol added no pose prior");
    const hamal::Pose2& p0 = prior->measurement();
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();  // hamal's error = d * GTSAM's
    d.topLeftCorner<2, 2>() = p0.R();
    factors.emplace_shared<gtsam::PriorFactor<gtsam::Pose2>>(
        gtsamKey(prior->keys()[0], "prior"), gtsam::Pose2(p0.x, p0.y, p0.theta),
        gtsam::noiseModel::Gaussian::Information(d.transpose() * prior->information() * d));

    gtsam::Values values;
    for (Key key : graph.keys()) {
      if (!point.initial.contains(key)) throw Error(FLAGS_values + ": no value for " + key.str());
      const hamal::Pose2 p = point.initial.pose(key);
      values.insert(gtsamKey(key, FLAGS_values), gtsam::Pose2(p.x, p.y, p.theta));
    }

    const Key last = protocol.pose(protocol.size() - 1);
    const gtsam::Key last_key = gtsamKey(last, FLAGS_data);
    using Clock = std::chrono::steady_clock;
    std::vector<double> construct, query;
    gtsam::Matrix body;
    for (int r = 0; r < FLAGS_repeat; ++r) {
      const auto t0 = Clock::now();
      const gtsam::Marginals marginals(factors, values);
      const auto t1 = Clock::now();
      body = marginals.marginalCovariance(last_key);
      const auto t2 = Clock::now();
      construct.push_back(std::chrono::duration<double>(t1 - t0).count());
      query.push_back(std::chrono::duration<double>(t2 - t1).count());
    }
    Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
    t.topLeftCorner<2, 2>() = point.initial.pose(last).R();
    const gtsam::Matrix world = t * body * t.transpose();

#ifdef GTSAM_VERSION_STRING
    const std::string version = GTSAM_VERSION_STRING;  // with the pre-release tag: 4.2a8
#else
    const std::string version = std::to_string(GTSAM_VERSION_MAJOR) + "." +
                                std::to_string(GTSAM_VERSION_MINOR) + "." +
                                std::to_string(GTSAM_VERSION_PATCH);
#endif
    std::printf("{\n  \"gtsam_version\": \"%s\",\n", version.c_str());
    std::printf("  \"key\": \"%s\",\n  \"repeat\": %d,\n", last.str().c_str(), FLAGS_repeat);
    printMatrix("covariance_body", body);
    printMatrix("covariance_world", world);
    std::printf("  \"construct_seconds\": %.9g,\n  \"query_seconds\": %.9g\n}\n", median(construct),
                median(query));
    return 0;
  });
}
