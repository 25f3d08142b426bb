// LagoInitialization: see lago_initialization.h (Carlone et al. 2014).
#include "protocol/lago_initialization.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/error.h"
#include "core/relative_pose_measurement.h"
#include "core/variable_prediction.h"

namespace hamal {

namespace {

constexpr double kTwoPi = 6.28318530717958647692;

struct Edge {
  int a, b;
  RelativePose z;
  const FactorPtr* factor;
};

// Whether `f` ties two or more poses (judged by the keys' kind), so that a
// reader would expect LAGO to use it.
bool joinsPoses(const Factor& f) {
  int poses = 0;
  for (Key k : f.keys()) poses += k.kind() == kPoseKind;
  return poses >= 2;
}

// Factors H x = g with the anchor's unknowns removed (they are fixed): the
// reduced system is SPD on a connected graph.
Eigen::VectorXd solveSpd(const std::vector<Eigen::Triplet<double>>& h, const Eigen::VectorXd& g,
                         const char* what) {
  Eigen::SparseMatrix<double> matrix(g.size(), g.size());
  matrix.setFromTriplets(h.begin(), h.end());
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt(matrix);
  if (llt.info() != Eigen::Success)
    throw Error(std::string("LAGO initialisation: the ") + what +
                " system is not positive definite");
  Eigen::VectorXd x = llt.solve(g);
  if (llt.info() != Eigen::Success || !x.allFinite())
    throw Error(std::string("LAGO initialisation: the ") + what + " system has no finite solution");
  return x;
}

// The relative-pose measurements LAGO uses, between poses indexed in key
// order (the anchor, the smallest key, first).
struct PoseGraph {
  std::vector<Key> keys;
  std::vector<Edge> edges;
  std::vector<std::vector<int>> incident;  // per pose, its edges
};

// The measurements of `factors` that LAGO can use; the others between poses
// go to result->unused with the reason. Throws when a used pose has no
// initial value or is not a pose.
PoseGraph poseGraph(const std::vector<FactorPtr>& factors, const Values& initial,
                    LagoResult* result) {
  PoseGraph graph;
  std::vector<Key>& keys = graph.keys;
  std::vector<std::pair<RelativePose, const FactorPtr*>> measurements;
  for (const FactorPtr& f : factors) {
    const std::optional<RelativePose> z = relativePoseOf(*f);
    if (!z) {
      if (joinsPoses(*f))
        result->unused.push_back(
            {f, "exposes no relative-pose measurement (RelativePoseMeasurement)"});
      continue;
    }
    if (f->lossFunction()) {
      result->unused.push_back(
          {f, "has a robust loss, which a linear least-squares solve ignores"});
      continue;
    }
    if (z->from == z->to) {
      result->unused.push_back({f, "ties a pose to itself"});
      continue;
    }
    measurements.emplace_back(*z, &f);
    keys.push_back(z->from);
    keys.push_back(z->to);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (keys.empty()) return graph;
  for (Key k : keys) {
    if (!initial.contains(k))
      throw Error("LAGO initialisation: pose " + k.str() + " has no initial value");
    if (initial.type(k) != VariableType::kPose2)
      throw Error("LAGO initialisation: " + k.str() +
                  " is in a relative-pose measurement but not a pose");
  }
  std::unordered_map<Key, int> index;
  for (std::size_t i = 0; i < keys.size(); ++i) index.emplace(keys[i], static_cast<int>(i));
  graph.incident.resize(keys.size());
  for (const auto& [z, f] : measurements) {
    const Edge e{index.at(z.from), index.at(z.to), z, f};
    graph.incident[e.a].push_back(static_cast<int>(graph.edges.size()));
    graph.incident[e.b].push_back(static_cast<int>(graph.edges.size()));
    graph.edges.push_back(e);
  }
  return graph;
}

// Step 1: headings composed along a breadth-first spanning tree from the
// anchor; `reached` marks the poses the tree reaches.
std::vector<double> treeHeadings(const PoseGraph& graph, double anchor_theta,
                                 std::vector<char>* reached) {
  const int n = static_cast<int>(graph.keys.size());
  std::vector<double> tree(n, 0.0);
  reached->assign(n, 0);
  std::deque<int> queue{0};
  tree[0] = anchor_theta;
  (*reached)[0] = 1;
  while (!queue.empty()) {
    const int u = queue.front();
    queue.pop_front();
    for (int ei : graph.incident[u]) {
      const Edge& e = graph.edges[ei];
      const int v = e.a == u ? e.b : e.a;
      if ((*reached)[v]) continue;
      const double z = e.z.measurement.theta;
      tree[v] = e.a == u ? tree[u] + z : tree[u] - z;
      (*reached)[v] = 1;
      queue.push_back(v);
    }
  }
  return tree;
}

// The unknowns of the linear systems: the reached poses but the anchor, by
// index (-1: the anchor or unreached).
struct Unknowns {
  std::vector<int> index;
  int count = 0;
};

// Step 2: the headings from the rotations unwrapped against the tree, the
// anchor's held; every pose's heading (the anchor's where unreached).
// Sets each used edge's covariance.
std::vector<double> solveHeadings(const PoseGraph& graph, const std::vector<double>& tree,
                                  const std::vector<char>& reached, const Unknowns& unknowns,
                                  double anchor_theta, std::vector<Eigen::Matrix3d>* covariance) {
  const std::vector<Edge>& edges = graph.edges;
  const std::vector<int>& unknown = unknowns.index;
  std::vector<Eigen::Triplet<double>> h;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(unknowns.count);
  auto add = [&](int i, int j, double v) {
    if (i >= 0 && j >= 0) h.emplace_back(i, j, v);
  };
  covariance->assign(edges.size(), Eigen::Matrix3d());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const Edge& e = edges[k];
    if (!reached[e.a]) continue;  // a component without the anchor
    (*covariance)[k] = e.z.information.inverse();
    const double w = 1.0 / (*covariance)[k](2, 2);
    const double z = e.z.measurement.theta;
    const double d = z + kTwoPi * std::round((tree[e.b] - tree[e.a] - z) / kTwoPi);
    // Residual th_b - th_a - d, with the anchor's heading a known constant.
    const int ia = unknown[e.a], ib = unknown[e.b];
    const double known = (ia < 0 ? -anchor_theta : 0.0) + (ib < 0 ? anchor_theta : 0.0);
    add(ia, ia, w);
    add(ib, ib, w);
    add(ia, ib, -w);
    add(ib, ia, -w);
    if (ia >= 0) g[ia] -= w * (d - known);
    if (ib >= 0) g[ib] += w * (d - known);
  }
  const Eigen::VectorXd theta_solution = solveSpd(h, g, "orientation");
  std::vector<double> theta(graph.keys.size(), anchor_theta);
  for (std::size_t v = 1; v < graph.keys.size(); ++v)
    if (reached[v]) theta[v] = theta_solution[unknown[v]];
  return theta;
}

// Step 3: the positions with those headings, the anchor's held; two rows
// per unknown.
Eigen::VectorXd solvePositions(const PoseGraph& graph, const std::vector<double>& theta,
                               const std::vector<char>& reached, const Unknowns& unknowns,
                               const Pose2& anchor,
                               const std::vector<Eigen::Matrix3d>& covariance) {
  const std::vector<Edge>& edges = graph.edges;
  const std::vector<int>& unknown = unknowns.index;
  std::vector<Eigen::Triplet<double>> h;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(2 * unknowns.count);
  auto add = [&](int i, int j, double v) {
    if (i >= 0 && j >= 0) h.emplace_back(i, j, v);
  };
  const Eigen::Vector2d anchor_t(anchor.x, anchor.y);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const Edge& e = edges[k];
    if (!reached[e.a]) continue;
    const Eigen::Rotation2Dd rot(theta[e.a]);
    const Eigen::Matrix2d r = rot.toRotationMatrix();
    const Eigen::Matrix2d w = r * covariance[k].topLeftCorner<2, 2>().inverse() * r.transpose();
    const Pose2& z = e.z.measurement;
    // Residual t_b - t_a - r z_t, the anchor's position a known constant.
    Eigen::Vector2d c = r * Eigen::Vector2d(z.x, z.y);
    const int ia = unknown[e.a], ib = unknown[e.b];
    if (ia < 0) c += anchor_t;  // t_b - (anchor + r z)
    if (ib < 0) c -= anchor_t;  // (anchor) - t_a - r z
    for (int s = 0; s < 2; ++s)
      for (int t = 0; t < 2; ++t) {
        add(ia < 0 ? -1 : 2 * ia + s, ia < 0 ? -1 : 2 * ia + t, w(s, t));
        add(ib < 0 ? -1 : 2 * ib + s, ib < 0 ? -1 : 2 * ib + t, w(s, t));
        add(ia < 0 || ib < 0 ? -1 : 2 * ia + s, 2 * ib + t, -w(s, t));
        add(ia < 0 || ib < 0 ? -1 : 2 * ib + s, 2 * ia + t, -w(s, t));
      }
    const Eigen::Vector2d wc = w * c;
    if (ia >= 0) g.segment<2>(2 * ia) -= wc;
    if (ib >= 0) g.segment<2>(2 * ib) += wc;
  }
  return solveSpd(h, g, "position");
}

// Variables that hang off the solved poses (landmarks) follow them: each is
// predicted again from its first factor whose other keys are placed, as
// the thesis protocol initialises it, so that a landmark keeps its place
// relative to the pose that saw it.
void followPlaced(const std::vector<FactorPtr>& factors, const Values& initial,
                  std::unordered_map<Key, char>* placed, LagoResult* result) {
  for (const FactorPtr& f : factors) {
    Key open{};
    int unplaced = 0;
    for (Key k : f->keys())
      if (!placed->count(k)) open = k, ++unplaced;
    if (unplaced != 1 || !initial.contains(open)) continue;
    Values::Entry guess = initial.entry(open);
    if (predictVariable(*f, open, result->values, &guess)) {
      result->values.setEntry(open, guess);
      placed->emplace(open, 1);
      ++result->followed;
    }
  }
}

}  // namespace

LagoResult lagoInitialization(const std::vector<FactorPtr>& factors, const Values& initial) {
  LagoResult result;
  result.values = initial;
  const PoseGraph graph = poseGraph(factors, initial, &result);
  const std::vector<Key>& keys = graph.keys;
  if (keys.empty()) return result;
  const int n = static_cast<int>(keys.size());

  const Pose2 anchor = initial.pose(keys[0]);
  std::vector<char> reached;
  const std::vector<double> tree = treeHeadings(graph, anchor.theta, &reached);
  Unknowns unknowns;
  unknowns.index.assign(n, -1);
  for (int v = 1; v < n; ++v)
    if (reached[v]) unknowns.index[v] = unknowns.count++;
  result.poses = static_cast<std::size_t>(unknowns.count) + 1;
  for (const Edge& e : graph.edges) {
    if (reached[e.a])
      ++result.edges;
    else
      result.unused.push_back(
          {*e.factor,
           "lies in a part of the pose graph not connected to the anchor " + keys[0].str()});
  }
  if (unknowns.count == 0) return result;

  std::vector<Eigen::Matrix3d> covariance;
  const std::vector<double> theta =
      solveHeadings(graph, tree, reached, unknowns, anchor.theta, &covariance);
  const Eigen::VectorXd t = solvePositions(graph, theta, reached, unknowns, anchor, covariance);
  std::unordered_map<Key, char> placed;  // solved here, or predicted from what was
  for (int v = 0; v < n; ++v) {
    if (!reached[v]) continue;
    placed.emplace(keys[v], 1);
    if (v == 0) continue;
    const int u = unknowns.index[v];
    result.values.set(keys[v], Pose2(t[2 * u], t[2 * u + 1], wrapAngle(theta[v])));
  }
  followPlaced(factors, initial, &placed, &result);
  return result;
}

std::string describe(const LagoResult& result) {
  std::string out = "LAGO used " + std::to_string(result.edges) + " of " +
                    std::to_string(result.edges + result.unused.size()) +
                    " factors between poses (" + std::to_string(result.poses) + " poses placed)";
  if (result.unused.empty()) return out;
  std::map<std::pair<std::string, std::string>, std::size_t> counts;  // (tag, reason)
  for (const auto& u : result.unused) ++counts[{u.factor->tag(), u.reason}];
  out += "; not used:";
  const char* sep = " ";
  for (const auto& [what, count] : counts) {
    out += sep + std::to_string(count) + " " + what.first + " (" + what.second + ")";
    sep = ", ";
  }
  return out;
}

}  // namespace hamal
