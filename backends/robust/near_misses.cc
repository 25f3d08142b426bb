// NearMisses: see near_misses.h.
#include "backends/robust/near_misses.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.h"

namespace hamal::robust {
namespace {

// Calls own(i, G_ii) for each of `factors` with its own block of G (made
// symmetric), asking the back-end in blocks of kNearMissBlock closures;
// false when it gives none or `own` returns false.
bool ownCovariances(FactorWeights& weights, const std::vector<const Factor*>& factors,
                    const std::function<bool(std::size_t, const Eigen::MatrixXd&)>& own) {
  for (std::size_t first = 0; first < factors.size(); first += kNearMissBlock) {
    const std::size_t last = std::min(factors.size(), first + kNearMissBlock);
    const std::vector<const Factor*> block(factors.begin() + first, factors.begin() + last);
    int rows = 0;
    for (const Factor* f : block) rows += f->residualDim();
    Eigen::MatrixXd g;
    if (!weights.residualCovariance(block, &g) || g.rows() != rows || g.cols() != rows ||
        !g.allFinite())
      return false;
    int offset = 0;
    for (std::size_t i = 0; i < block.size(); ++i) {
      const int d = block[i]->residualDim();
      const Eigen::MatrixXd gi =
          0.5 * (g.block(offset, offset, d, d) + g.block(offset, offset, d, d).transpose());
      if (!own(first + i, gi)) return false;
      offset += d;
    }
  }
  return true;
}

}  // namespace

double nearMissWeight(double k, int dim) {
  if (!(k > 1)) return 1;  // inside the ball, or not a number: count it fully
  return std::pow(k, -0.5 * dim);
}

std::optional<double> expectedFalseAcceptances(FactorWeights& weights,
                                               const std::vector<const Factor*>& rejected,
                                               const std::vector<double>& c2,
                                               const Values& estimate) {
  if (c2.size() != rejected.size())
    throw Error("expectedFalseAcceptances: " + std::to_string(rejected.size()) + " closures but " +
                std::to_string(c2.size()) + " thresholds");
  double expected = 0;
  const bool made = ownCovariances(weights, rejected, [&](std::size_t i, const Eigen::MatrixXd& g) {
    const int d = rejected[i]->residualDim();
    Eigen::VectorXd r(d);
    try {
      if (!rejected[i]->evaluate(estimate, r.data()) || !r.allFinite()) return false;
    } catch (const Error&) {
      return false;  // a variable the estimate does not hold
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(Eigen::MatrixXd::Identity(d, d) + g);
    if (ldlt.info() != Eigen::Success) return false;
    expected += nearMissWeight(r.dot(ldlt.solve(r)) / c2[i], d);
    return true;
  });
  if (!made) return std::nullopt;
  return expected;
}

std::optional<std::size_t> closuresAlone(FactorWeights& weights,
                                         const std::vector<const Factor*>& accepted) {
  std::vector<const Factor*> held;
  for (const Factor* f : accepted) {
    try {
      if (weights.factorWeight(f) >= 0.5) held.push_back(f);
    } catch (const Error&) {
      // not held by the back-end: no leverage of its own
    }
  }
  std::size_t alone = 0;
  const bool made = ownCovariances(weights, held, [&](std::size_t, const Eigen::MatrixXd& g) {
    alone += Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(g, Eigen::EigenvaluesOnly)
                 .eigenvalues()
                 .maxCoeff() > kAloneLeverage;
    return true;
  });
  if (!made) return std::nullopt;
  return alone;
}

std::optional<Refutation> refutation(FactorWeights& weights,
                                     const std::vector<const Factor*>& rejected,
                                     const std::vector<double>& c2,
                                     const std::vector<const Factor*>& accepted,
                                     const Values& estimate) {
  const std::optional<double> expected = expectedFalseAcceptances(weights, rejected, c2, estimate);
  if (!expected) return std::nullopt;
  const std::optional<std::size_t> alone = closuresAlone(weights, accepted);
  if (!alone) return std::nullopt;
  return Refutation{*expected, *alone};
}

}  // namespace hamal::robust
