// GraduatedNonConvexity's closing verdict (core/closing_verdict.h): at the
// end of a run it re-solves the alternative when closures came since the
// last check, once, and never with gnc_doubt=off.
#include "core/closing_verdict.h"

#include <gtest/gtest.h>

#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::robust {
namespace {

struct GncRun {
  std::unique_ptr<Backend> backend;
  GraduatedNonConvexity* gnc = nullptr;
};

// GNC over aprilsam stepped through a spoiled world by hand (not the step
// runner, which asks for the verdict itself), then one more step that
// brings a single false closure: too few new closures for the update's own
// schedule to re-solve the alternative.
GncRun runWithALateClosure(const std::string& spec) {
  static Registry base = [] {
    Registry r;
    apps::setUpRegistry(r, {});
    return r;
  }();
  apps::ManhattanWorldOptions m;
  m.poses = 200;
  m.seed = 2;
  const Graph clean = apps::generateManhattanWorld(m).graph;
  apps::SpoilOptions o;
  o.outliers = 20;
  o.seed = 3;
  const apps::SpoiledGraph spoiled = apps::spoilGraph(clean, o);
  const Registry r = apps::robustRegistry(base);
  GncRun run;
  run.backend = r.makeBackend(spec);
  run.gnc = dynamic_cast<GraduatedNonConvexity*>(run.backend.get());
  const ThesisProtocol protocol(spoiled.graph);
  for (std::size_t i = 0; i < protocol.size(); ++i)
    EXPECT_NE(run.backend->update(protocol.step(i, run.backend->estimate())).status.code,
              Status::kNumericalFailure);
  Step late;
  late.index = protocol.size();
  late.new_factors.push_back(std::make_shared<BetweenFactor>(X(3), X(150), Pose2(40, -25, 2),
                                                             Eigen::Matrix3d::Identity() * 100));
  run.backend->update(late);
  return run;
}

TEST(ClosingVerdict, GncChecksTheClosuresSinceItsLastCheckOnce) {
  GncRun run = runWithALateClosure("aprilsam:robust=gnc");
  ASSERT_NE(run.gnc, nullptr);
  const long before = run.gnc->alternativesChecked();
  run.gnc->closingVerdict();
  EXPECT_EQ(run.gnc->alternativesChecked(), before + 1);
  run.gnc->closingVerdict();  // nothing came since
  EXPECT_EQ(run.gnc->alternativesChecked(), before + 1);
}

TEST(ClosingVerdict, GncWithDoubtOffChecksNothing) {
  GncRun run = runWithALateClosure("aprilsam:robust=gnc,gnc_doubt=off");
  ASSERT_NE(run.gnc, nullptr);
  EXPECT_TRUE(run.gnc->closingVerdict().ok());
  EXPECT_EQ(run.gnc->alternativesChecked(), 0);
}

}  // namespace
}  // namespace hamal::robust
