// ThesisProtocol: the incremental view of a graph that every figure uses
// (docs/PROTOCOL.md, "The thesis protocol"; thesis sec. 3.5.1).
//
//  1. The first pose gets a prior at its initial value ((0,0,0) without
//     vertices) with information diag(1e4, 1e4, 1e3).
//  2. Poses are taken in increasing id order. Step i initialises pose i by
//     composing the current estimate of pose i-1 with the odometry factor
//     between them (any factor that can predict pose i from known variables
//     when there is no such edge), and adds every factor whose newest pose
//     is pose i. A landmark enters with the first factor that observes it
//     and is initialised from that observation.
//  3. The caller runs exactly one back-end update per step.
//
// Fixed variables (the graph's FIX lines, Graph::fixed) enter the step that
// adds them as Step::fixed, at the graph's value for them (the composed guess
// when the graph has none). A graph that fixes a pose has its gauge fixed,
// so the protocol adds no prior then; fixed landmarks alone leave the
// rotation free, and the prior stays.
//
// Because guesses come from the back-end's current estimate, a step is made
// on demand: step(i, backend.estimate()). It is the StepSource
// (core/step_source.h) of every figure made from a dataset; its steps depend
// on nothing but `estimate`, so it can also be stepped through a const
// reference (initialValues, batch).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <set>
#include <vector>

#include "core/graph.h"
#include "core/step.h"
#include "core/step_source.h"

namespace hamal {

class ThesisProtocol : public StepSource {
 public:
  struct Options {
    bool add_prior = true;
    Eigen::Vector3d prior_information{1e4, 1e4, 1e3};  // diagonal
  };

  // Throws hamal::Error when the graph cannot be stepped through (no pose, a
  // pose or landmark that no factor connects to what came before).
  explicit ThesisProtocol(const Graph& graph);
  ThesisProtocol(const Graph& graph, Options options);

  // Number of steps: one per pose (step 0 holds the first pose and the prior).
  std::size_t size() const override { return plan_.size(); }
  // Step i, its guesses composed from `estimate` (which must hold every
  // variable of steps < i).
  Step step(std::size_t i, const Values& estimate) const;
  Step step(std::size_t i, const Values& estimate) override {
    return static_cast<const ThesisProtocol&>(*this).step(i, estimate);
  }

  // Odometry-composed guesses for every variable: where batch solves start.
  Values initialValues() const;
  // Everything in one step, from initialValues(): a batch solve.
  Step batch() const;

  // The prior the protocol adds (nullptr without one). Not a dataset factor:
  // chi2 figures exclude it.
  const FactorPtr& prior() const { return prior_; }
  // The pose of step i.
  Key pose(std::size_t i) const { return plan_[i].pose; }

 private:
  struct Plan {
    Key pose;
    const Factor* initialiser = nullptr;                   // nullptr for the first pose
    std::vector<std::pair<Key, const Factor*>> landmarks;  // new landmark, its first observation
    std::vector<FactorPtr> factors;
  };
  void fill(std::size_t i, const Values& estimate, Step* out) const;

  std::vector<Plan> plan_;
  std::set<Key> fixed_;
  Values fixed_values_;  // the graph's values of its fixed variables
  FactorPtr prior_;
  Pose2 first_pose_;
};

}  // namespace hamal
