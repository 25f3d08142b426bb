// Figs. 4.8 and 4.10's trials are recordings made by hand (point
// measurements, data_association_experiments.h), not scans: the detector
// option cannot change them, as apps/flag/README.md states. Their ray-cast
// scenes (--raycast) are seen by the detector: the person walks the
// hand-made line past a corner in view all along; the cabinet stands where
// fig. 4.9 puts it and the scan detector sees its edges.
#include <gtest/gtest.h>

#include "apps/flag/data_association_experiments.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

// A scene as the trials see it: the scan detector, 4 m.
flag::Recording scanned(const flag::FloorPlan& plan, std::uint64_t seed) {
  flag::SimulatorOptions sim;
  sim.seed = seed;
  sim.sensor_range = 4.0;
  return flag::simulate(plan, sim);
}

TEST(RayCastDynamicObstacle, ThePersonWalksPastACornerInViewAllAlong) {
  std::size_t poses = 0, corner_seen = 0, person_seen = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const flag::FloorPlan plan = flag::dynamicObstaclePlan(seed, 0.1, 2.0);
    ASSERT_EQ(plan.corners.size(), 1u);
    ASSERT_EQ(plan.people.size(), 1u);
    const flag::Person& p = plan.people[0];
    const Point2 c = plan.corners[0].truth, d = (p.to - p.from).normalized();
    EXPECT_NEAR((p.to - p.from).norm(), 1.0, 1e-9);
    const double side = std::abs(d.x() * (c - p.from).y() - d.y() * (c - p.from).x());
    EXPECT_GE(side, 0.1 - 1e-9);
    EXPECT_LE(side, 0.4 + 1e-9);
    const flag::Recording rec = scanned(plan, seed);
    ASSERT_EQ(rec.steps.size(), 10u);
    Point2 at;
    EXPECT_TRUE(p.at(rec.steps.back().time, &at));  // walking until the last pose
    for (const flag::RecordedStep& s : rec.steps) {
      ++poses;
      bool corner = false, person = false;
      for (const flag::Detection& det : s.detections) {
        corner |= det.source.kind == flag::Source::kCorner;
        person |= det.source.kind == flag::Source::kPerson;
      }
      corner_seen += corner;
      person_seen += person;
    }
  }
  EXPECT_GT(corner_seen, poses / 2);  // unless the person stands in front of it
  EXPECT_GT(person_seen, 0u);
}

TEST(RayCastStaticObstacle, TheCabinetStandsBeforeTheLastCornerAndIsSeen) {
  std::size_t object_detections = 0, last_corner = 0, other_corners = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const flag::FloorPlan plan = flag::staticObstaclePlan(seed, 0.5, 0.1);
    ASSERT_TRUE(plan.corners.size() == 4 && plan.objects.size() == 1);
    const Point2 corner = plan.corners[3].truth, at = plan.objects[0].position;
    EXPECT_LE((at - corner).norm(), 0.5);
    EXPECT_LE(at.x(), corner.x());  // on the drive's side of the corner
    EXPECT_GE(at.y(), corner.y());
    EXPECT_LT((plan.corners[3].label - corner).norm(), 0.5);
    for (const flag::RecordedStep& s : scanned(plan, seed).steps)
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

TEST(RayCastTrials, TheDetectorChangesThemAndTheirOptionsAreChecked) {
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
  const testing::CommandResult office = testing::runCommand(testing::buildPath("apps/hamal_flag") +
                                                            " trials office --raycast --trials 1");
  EXPECT_EQ(office.status, 1);
  EXPECT_NE(office.output.find("only the dynamic and static experiments"), std::string::npos)
      << office.output;
  const std::string dynamic =
      testing::buildPath("apps/hamal_flag") + " trials dynamic --raycast --trials 2";
  const testing::CommandResult dynamic_scan = testing::runCommand(dynamic);
  ASSERT_EQ(dynamic_scan.status, 0) << dynamic_scan.output;
  EXPECT_NE(dynamic_scan.output, testing::runCommand(dynamic + " --detector oracle").output);
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
