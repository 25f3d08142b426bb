// LagoInitialization: initial values for a 2D pose graph from two linear
// least-squares problems, orientations first, then positions (Carlone,
// Aragues, Castellanos, Bona: "A fast and accurate approximation for planar
// pose graph optimization", IJRR 2014; GTSAM's lago::initialize).
//
// Why: a batch solve from odometry-composed values (docs/PROTOCOL.md) needs the
// composed headings to be near the optimum. Over 10^6 noisy odometry steps
// the heading drifts by radians, and Gauss-Newton from there stalls in a
// wrong basin (the scale study's 10^6-pose world: chi2 4.6e9 after 20
// iterations). LAGO's orientations see every loop closure at once, so
// Gauss-Newton starts next to the optimum and needs a few iterations.
//
// Method, on the factors that expose a relative-pose measurement between two
// Pose2 variables (RelativePoseMeasurement: EDGE_SE2 and its kin) and carry no
// robust loss; the rest of the graph is left as it is, and every factor
// between poses that is not used is listed with the reason in
// LagoResult::unused, so that a max-mixture, a robust or a plugin's edge is
// never dropped without a word:
//   1. A spanning tree by breadth-first search from the anchor (the pose with
//      the smallest key, held at its value in `initial`) gives every pose a
//      heading th~ by composing the measured rotations.
//   2. Each edge's measured rotation z_th is unwrapped against the tree:
//      d_ab = z_th + 2 pi round((th~_b - th~_a - z_th) / 2 pi), and the
//      headings solve  min sum w_ab (th_b - th_a - d_ab)^2  with the
//      anchor fixed; w_ab = 1 / Sigma_thth, Sigma = Omega^-1.
//   3. With those headings, the positions solve the linear problem
//      min sum |t_b - t_a - R(th_a) z_t|^2 weighted by R(th_a) Sigma_tt^-1
//      R(th_a)^T, the anchor fixed.
// Both systems are sparse SPD, solved by CHOLMOD's supernodal Cholesky
// through Eigen's CholmodSupport, several times faster than Eigen's own
// simplicial LDL^T on the 10^6-pose world.
//
// Then every other variable with an initial value (a landmark) is predicted
// again from its first factor whose other variables are placed (the pose
// that first saw it), as the thesis protocol initialises it. Poses not
// connected to the anchor through used measurements, and what hangs only off
// them, keep their values from `initial`.
#pragma once

#include <string>
#include <vector>

#include "core/graph.h"
#include "core/values.h"

namespace hamal {

struct LagoResult {
  Values values;             // `initial` with every connected pose replaced
  std::size_t poses = 0;     // poses solved (connected to the anchor)
  std::size_t edges = 0;     // relative-pose measurements used
  std::size_t followed = 0;  // other variables predicted again from the solved poses
  // Factors between two or more poses that were not used, each with why:
  // no relative-pose measurement, a robust loss, a pose tied to itself, or a
  // part of the graph the anchor does not reach.
  struct Unused {
    FactorPtr factor;
    std::string reason;
  };
  std::vector<Unused> unused;
};

// Throws hamal::Error when `initial` lacks a pose that a used measurement
// names, or when a linear system cannot be factored.
LagoResult lagoInitialization(const std::vector<FactorPtr>& factors, const Values& initial);
inline LagoResult lagoInitialization(const Graph& graph, const Values& initial) {
  return lagoInitialization(graph.factors, initial);
}

// One line for a person: what was used, and the unused factors counted by
// tag and reason ("LAGO used 5453 of 5456 factors between poses; not used:
// 3 EDGE_SE2_CAUCHY (has a robust loss, ...)").
std::string describe(const LagoResult& result);

}  // namespace hamal
