// Figs. 4.8 and 4.10's trials are recordings made by hand (point
// measurements, data_association_experiments.h), not scans: the detector
// option cannot change them, as apps/flag/README.md states. Fig. 4.10's
// ray-cast scene (--raycast) is seen by the detector: the cabinet stands
// where fig. 4.9 puts it and the scan detector sees its edges.
#include <gtest/gtest.h>

#include "apps/flag/data_association_experiments.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

TEST(RayCastStaticObstacle, TheCabinetStandsBeforeTheLastCornerAndIsSeen) {
  std::size_t object_detections = 0, last_corner = 0, other_corners = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const flag::FloorPlan plan = flag::staticObstaclePlan(seed, 0.5, 0.1);
    ASSERT_EQ(plan.corners.size(), 4u);
    ASSERT_EQ(plan.objects.size(), 1u);
    const Point2 corner = plan.corners[3].truth, at = plan.objects[0].position;
    EXPECT_LE((at - corner).norm(), 0.5);
    EXPECT_LE(at.x(), corner.x());  // on the drive's side of the corner
    EXPECT_GE(at.y(), corner.y());
    EXPECT_LT((plan.corners[3].label - corner).norm(), 0.5);
    flag::SimulatorOptions sim;
    sim.seed = seed;
    sim.sensor_range = 4.0;
    for (const flag::RecordedStep& s : flag::simulate(plan, sim).steps)
      for (const flag::Detection& d : s.detections) {
        object_detections += d.source.kind == flag::Source::kObject;
        if (d.source.kind == flag::Source::kCorner)
          ++(d.source.id == 3 ? last_corner : other_corners);
      }
  }
  EXPECT_GT(object_detections, 20u);      // the cabinet's edges, at least one a trial
  EXPECT_GT(other_corners, 20u * 3 * 4);  // the unobstructed corners, seen from several poses
  EXPECT_LT(last_corner, other_corners / 3);
}

TEST(RayCastStaticObstacle, TheDetectorChangesItAndItsOptionsAreChecked) {
  const std::string trials =
      testing::buildPath("apps/hamal_flag") + " trials static --raycast --trials 2";
  const testing::CommandResult scan = testing::runCommand(trials + " --detector scan");
  const testing::CommandResult oracle = testing::runCommand(trials + " --detector oracle");
  ASSERT_EQ(scan.status, 0) << scan.output;
  ASSERT_EQ(oracle.status, 0) << oracle.output;
  EXPECT_NE(scan.output, oracle.output);
  const testing::CommandResult stated = testing::runCommand(trials + " --stated_sigma 0.05");
  EXPECT_EQ(stated.status, 1);
  EXPECT_NE(stated.output.find("--stated_sigma: the ray-cast scene"), std::string::npos)
      << stated.output;
  const testing::CommandResult dynamic = testing::runCommand(
      testing::buildPath("apps/hamal_flag") + " trials dynamic --raycast --trials 1");
  EXPECT_EQ(dynamic.status, 1);
  EXPECT_NE(dynamic.output.find("only the static experiment"), std::string::npos) << dynamic.output;
}

TEST(HandMadeTrials, TheDetectorDoesNotChangeFigs48And410) {
  const std::string flag = testing::buildPath("apps/hamal_flag");
  for (const char* experiment : {"dynamic", "static"}) {
    const std::string trials = flag + " trials " + experiment + " --trials 2";
    const testing::CommandResult scan = testing::runCommand(trials + " --detector scan");
    const testing::CommandResult oracle = testing::runCommand(trials + " --detector oracle");
    ASSERT_EQ(scan.status, 0) << scan.output;
    ASSERT_EQ(oracle.status, 0) << oracle.output;
    EXPECT_GT(scan.output.size(), 100u);
    EXPECT_EQ(scan.output, oracle.output) << experiment;
  }
}

}  // namespace
}  // namespace hamal
