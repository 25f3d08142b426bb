// GNC's adoption of the noise scale's alternative (graduated_non_convexity.h,
// gnc_noise_scale; backends/robust/NOISE_SCALE.md): where the stated
// informations overstate the noise 50 times (as M3500's do), incremental
// GNC at the stated c2 keeps part of a false group that bends the map within
// c2; at the end of the run the alternative solved at c2 scaled by the
// answer's variance factor is cheaper there, and adopting it (its decisions
// made at the stated c2) ends at the clean map, where the plain alternative,
// cheaper only at the stated c2, is no doubt. Reporting it instead leaves the
// bent answer, uncertain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <string>

#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "core/closing_verdict.h"
#include "protocol/thesis_protocol.h"
#include "tests/robust/spoiled_world.h"

namespace hamal::robust {
namespace {

struct Outcome {
  Status status;
  std::size_t false_accepted = 0, true_rejected = 0;
  double largest_move = 0;  // from the clean optimum, m
};

Outcome run(const testing::SpoiledWorld& w, const std::string& spec) {
  const std::unique_ptr<Backend> backend = apps::robustRegistry(w.registry).makeBackend(spec);
  const auto* gnc = dynamic_cast<const GraduatedNonConvexity*>(backend.get());
  EXPECT_NE(gnc, nullptr);
  Outcome out;
  const ThesisProtocol protocol(w.spoiled.graph);
  for (std::size_t i = 0; i < protocol.size(); ++i)
    out.status = backend->update(protocol.step(i, backend->estimate())).status;
  if (out.status.ok())
    if (auto* verdict = dynamic_cast<ClosingVerdict*>(backend.get()))
      out.status = verdict->closingVerdict();
  std::set<const Factor*> true_closures;
  for (const FactorPtr& f : w.clean.factors)
    if (isLoopClosure(*f)) true_closures.insert(f.get());
  for (const GraduatedNonConvexity::Decision& d : gnc->decisions()) {
    const bool in = d.weight >= 0.5;
    if (true_closures.count(d.factor))
      out.true_rejected += !in;
    else
      out.false_accepted += in;
  }
  for (const auto& [key, entry] : w.clean_optimum) {
    const Pose2 a = w.clean_optimum.pose(key), b = backend->estimate().pose(key);
    out.largest_move = std::max(out.largest_move, std::hypot(a.x - b.x, a.y - b.y));
  }
  return out;
}

testing::SpoiledWorld world(double information_scale, apps::SpoilPolicy policy,
                            std::uint64_t seed) {
  testing::SpoiledWorldOptions o;
  o.information_scale = information_scale;
  o.outliers = 30;
  o.policy = policy;
  o.spoil_seed = seed;
  return testing::makeSpoiledWorld(o);
}

const std::string kReport = "aprilsam:robust=gnc,gnc_noise_scale=report";
const std::string kAdopt = "aprilsam:robust=gnc";  // the default

TEST(NoiseScaleAdoption, TheAlternativeAtTheDataScaleUnbendsAFalseGroup) {
  const testing::SpoiledWorld w = world(0.02, apps::SpoilPolicy::kLocalGroup, 3);
  const Outcome reported = run(w, kReport);
  EXPECT_EQ(reported.status.code, Status::kUncertain);
  EXPECT_NE(reported.status.message.find("noise scale"), std::string::npos)
      << reported.status.message;
  EXPECT_GE(reported.false_accepted, 1u);
  EXPECT_GT(reported.largest_move, 1.0);
  const Outcome adopted = run(w, kAdopt);
  EXPECT_TRUE(adopted.status.ok()) << adopted.status.message;
  EXPECT_EQ(adopted.false_accepted, 0u);
  EXPECT_EQ(adopted.true_rejected, 0u);
  EXPECT_LT(adopted.largest_move, 0.01);
}

TEST(NoiseScaleAdoption, ARightAnswerIsJudgedAtTheDataScale) {
  // The right answer, but a map cheaper at the stated c2 (a false group
  // kept within it) stands against it; at the scaled c2 it is not cheaper.
  const testing::SpoiledWorld w = world(0.02, apps::SpoilPolicy::kRandomGroup, 6);
  const Outcome reported = run(w, kReport);
  EXPECT_EQ(reported.false_accepted, 0u);
  EXPECT_EQ(reported.status.code, Status::kUncertain);
  EXPECT_NE(reported.status.message.find("a cheaper alternative"), std::string::npos)
      << reported.status.message;
  const Outcome adopted = run(w, kAdopt);
  EXPECT_TRUE(adopted.status.ok()) << adopted.status.message;
  EXPECT_EQ(adopted.false_accepted, 0u);
  EXPECT_LT(adopted.largest_move, 0.01);
}

TEST(NoiseScaleAdoption, WhereTheInformationsAreTheNoisesNothingChanges) {
  for (const apps::SpoilPolicy policy :
       {apps::SpoilPolicy::kLocalGroup, apps::SpoilPolicy::kRandomGroup}) {
    const testing::SpoiledWorld w = world(1, policy, 3);
    const Outcome reported = run(w, kReport), adopted = run(w, kAdopt);
    EXPECT_EQ(reported.status.code, adopted.status.code);
    EXPECT_EQ(reported.false_accepted, adopted.false_accepted);
    EXPECT_EQ(reported.true_rejected, adopted.true_rejected);
    EXPECT_DOUBLE_EQ(reported.largest_move, adopted.largest_move);
  }
}

}  // namespace
}  // namespace hamal::robust
