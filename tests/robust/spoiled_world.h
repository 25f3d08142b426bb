// Test-local helper of the robust suite: the spoiled world several of its
// tests run on. A generated Manhattan world whose stated informations may be
// scaled against the generator's true noise (0.02 on every factor overstates
// the covariances 50 times, as M3500's; 0.01 on the loop closures alone makes
// them as uncertain next to the odometry as M3500's), spoiled with false loop
// closures (apps/robust/false_loop_closures.h), and the clean graph's batch
// optimum. One builder, so the tests that share a world build it alike; each
// test says why it picks its scale.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <memory>

#include "apps/bench/bench_runner.h"
#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "backends/robust/loop_closure.h"
#include "core/graph.h"
#include "core/registry.h"
#include "core/values.h"
#include "factors/between_factor.h"

namespace hamal::testing {

// Which stated informations information_scale multiplies.
enum class ScaledFactors { kAll, kLoopClosures };

struct SpoiledWorldOptions {
  std::size_t poses = 300;  // the Manhattan world
  std::uint64_t seed = 3;
  double information_scale = 1;  // 1: the generator's own informations
  ScaledFactors scaled = ScaledFactors::kAll;
  std::size_t outliers = 30;  // false loop closures (apps::SpoilOptions)
  apps::SpoilPolicy policy = apps::SpoilPolicy::kRandom;
  std::uint64_t spoil_seed = 5;
};

struct SpoiledWorld {
  Registry registry;  // the built-in back-ends, no plugins
  Graph clean;        // the generated graph, its informations scaled
  apps::SpoiledGraph spoiled;
  Values clean_optimum;  // cholesky's batch optimum of `clean`
};

// Every chosen factor's information times `scale`; the generator writes
// only BetweenFactors, so a chosen factor of another type throws.
inline void scaleInformation(Graph& graph, double scale, ScaledFactors scaled) {
  for (auto& f : graph.factors) {
    if (scaled == ScaledFactors::kLoopClosures && !robust::isLoopClosure(*f)) continue;
    const auto& b = dynamic_cast<const BetweenFactor&>(*f);
    f = std::make_shared<BetweenFactor>(b.keys()[0], b.keys()[1], b.measurement(),
                                        scale * b.information());
  }
}

inline SpoiledWorld makeSpoiledWorld(const SpoiledWorldOptions& options) {
  SpoiledWorld out;
  apps::setUpRegistry(out.registry, {});
  apps::ManhattanWorldOptions m;
  m.poses = options.poses;
  m.seed = options.seed;
  out.clean = apps::generateManhattanWorld(m).graph;
  if (options.information_scale != 1)
    scaleInformation(out.clean, options.information_scale, options.scaled);
  apps::SpoilOptions s;
  s.outliers = options.outliers;
  s.policy = options.policy;
  s.seed = options.spoil_seed;
  out.spoiled = apps::spoilGraph(out.clean, s);
  const apps::BatchOptimum opt =
      apps::solveBatchOptimum(out.clean, ThesisProtocol(out.clean), 0, out.registry, "cholesky");
  EXPECT_TRUE(opt.status.ok()) << opt.status.message;
  out.clean_optimum = opt.estimate;
  return out;
}

}  // namespace hamal::testing
