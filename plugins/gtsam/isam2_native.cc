// hamal_isam2_native: GTSAM's iSAM2 driven directly, with no hamal code in
// the loop, under the thesis protocol (sec. 3.5; docs/PROTOCOL.md): prior on
// pose 0 with information diag(1e4, 1e4, 1e3), one ISAM2::update per pose with
// the edges that close at it, pose i guessed from iSAM2's estimate of pose
// i-1 composed with the odometry edge. Its purpose is a check of the plugin
// (isam2_backend.h): the same iSAM2 driven the way a GTSAM user would, so
// that a table's iSAM2 time is GTSAM's and not the adapter's.
//
//   hamal_isam2_native --data FILE [--full_estimate] [--repeat N]
//
// FILE (--data, or the only positional argument): a 2D pose graph in g2o (VERTEX_SE2 / EDGE_SE2) or
// TORO (VERTEX2 / EDGE2) form; any other tag is an error naming the line. Only ISAM2::update is
// timed as "update"; "estimate" is the estimate the protocol needs (calculateEstimate<Pose2>(i) by
// default, the whole calculateEstimate() with --full_estimate, as the plugin's step does). chi2 is
// GTSAM's own (2 x NonlinearFactorGraph::error, the measurement-frame residual), without the prior.
// With --repeat, times are medians.
#include <gflags/gflags.h>
#include <gtsam/geometry/Pose2.h>
#include <gtsam/nonlinear/ISAM2.h>
#include <gtsam/nonlinear/PriorFactor.h>
#include <gtsam/slam/BetweenFactor.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "core/error.h"

DEFINE_string(data, "",
              "the pose graph, g2o (VERTEX_SE2 / EDGE_SE2) or TORO (VERTEX2 / EDGE2) (or give it "
              "as the only positional argument)");
DEFINE_bool(full_estimate, false,
            "time the whole calculateEstimate() per step, as the plugin's step does, instead of "
            "calculateEstimate<Pose2>(i)");
DEFINE_int32(repeat, 1, "runs of the protocol; times are medians");

namespace {

struct Edge {
  int a = 0, b = 0;
  gtsam::Pose2 z;
  gtsam::Matrix3 information;
};

std::vector<Edge> readEdges(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::vector<Edge> edges;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag) || tag[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(n) + ": ";
    if (tag == "VERTEX_SE2" || tag == "VERTEX2") continue;  // guesses come from the protocol
    if (tag != "EDGE_SE2" && tag != "EDGE2")
      throw std::runtime_error(where + "tag " + tag + " is not a 2D pose-graph line");
    Edge e;
    double x, y, t, v[6];
    if (!(s >> e.a >> e.b >> x >> y >> t >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5]))
      throw std::runtime_error(where + "expected 2 ids, 3 numbers and 6 information entries");
    if (e.a < 0 || e.b < 0 || e.a == e.b) throw std::runtime_error(where + "bad pose ids");
    e.z = gtsam::Pose2(x, y, t);
    if (tag == "EDGE2")  // TORO: xx xy yy tt xt yt
      e.information << v[0], v[1], v[4], v[1], v[2], v[5], v[4], v[5], v[3];
    else  // g2o: xx xy xt yy yt tt
      e.information << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    edges.push_back(e);
  }
  if (edges.empty()) throw std::runtime_error(path + ": no edge");
  return edges;
}

struct Run {
  double update = 0, estimate = 0, chi2 = 0;
};

Run runProtocol(const std::vector<Edge>& edges, bool full_estimate) {
  int last = 0;
  for (const Edge& e : edges) last = std::max({last, e.a, e.b});
  std::vector<std::vector<int>> closing(last + 1);  // edges whose later pose is i
  for (int k = 0; k < static_cast<int>(edges.size()); ++k)
    closing[std::max(edges[k].a, edges[k].b)].push_back(k);
  using Clock = std::chrono::steady_clock;
  gtsam::ISAM2 isam{gtsam::ISAM2Params()};
  Run run;
  gtsam::Pose2 previous;
  for (int i = 0; i <= last; ++i) {
    gtsam::NonlinearFactorGraph graph;
    gtsam::Values guess;
    gtsam::Pose2 pose = previous;
    if (i == 0) {
      graph.add(gtsam::PriorFactor<gtsam::Pose2>(
          0, gtsam::Pose2(),
          gtsam::noiseModel::Diagonal::Precisions(gtsam::Vector3(1e4, 1e4, 1e3))));
      pose = gtsam::Pose2();
    } else {
      for (int k : closing[i]) {
        const Edge& e = edges[k];
        if (e.a == i - 1 && e.b == i) pose = previous.compose(e.z);
        if (e.b == i - 1 && e.a == i) pose = previous.compose(e.z.inverse());
      }
    }
    guess.insert(i, pose);
    for (int k : closing[i])
      graph.add(gtsam::BetweenFactor<gtsam::Pose2>(
          edges[k].a, edges[k].b, edges[k].z,
          gtsam::noiseModel::Gaussian::Information(edges[k].information)));
    const auto t0 = Clock::now();
    isam.update(graph, guess);
    const auto t1 = Clock::now();
    previous = full_estimate ? isam.calculateEstimate().at<gtsam::Pose2>(i)
                             : isam.calculateEstimate<gtsam::Pose2>(i);
    const auto t2 = Clock::now();
    run.update += std::chrono::duration<double>(t1 - t0).count();
    run.estimate += std::chrono::duration<double>(t2 - t1).count();
  }
  gtsam::NonlinearFactorGraph all;
  for (const Edge& e : edges)
    all.add(gtsam::BetweenFactor<gtsam::Pose2>(
        e.a, e.b, e.z, gtsam::noiseModel::Gaussian::Information(e.information)));
  run.chi2 = 2 * all.error(isam.calculateEstimate());
  return run;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_isam2_native", [&] {
    const auto positional = hamal::apps::parseCommandLine(
        &argc, &argv,
        "GTSAM's iSAM2 driven directly under the thesis protocol, a check of the gtsam "
        "plugin's times.\n\n  hamal_isam2_native --data FILE [--full_estimate] [--repeat N]");
    std::string path = FLAGS_data;
    if (positional.size() + (path.empty() ? 0 : 1) > 1)
      throw hamal::Error("give one pose graph (--data FILE or FILE)");
    if (path.empty() && positional.size() == 1) path = positional[0];
    if (path.empty()) throw hamal::Error("no input file: give --data FILE (see --help)");
    if (FLAGS_repeat < 1) throw hamal::Error("--repeat must be at least 1");
    const std::vector<Edge> edges = readEdges(path);
    std::vector<double> update, estimate;
    double chi2 = 0;
    for (int r = 0; r < FLAGS_repeat; ++r) {
      const Run run = runProtocol(edges, FLAGS_full_estimate);
      update.push_back(run.update);
      estimate.push_back(run.estimate);
      chi2 = run.chi2;
    }
    std::printf(
        "%s: iSAM2 (GTSAM directly), %d run(s): update %.3f s, estimate (%s) %.3f s, "
        "chi2 %.4f\n",
        path.c_str(), FLAGS_repeat, median(update), FLAGS_full_estimate ? "whole" : "pose i",
        median(estimate), chi2);
    return 0;
  });
}
