// Floor plans (apps/flag/floor_plan.h, builtin_worlds.h): the text format
// round-trips, the built-in worlds are what the thesis describes, and bad
// input is refused naming the file, line and reason.
#include "apps/flag/floor_plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "apps/flag/builtin_worlds.h"
#include "apps/flag/flag_options.h"
#include "apps/flag/simulator.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

const char kSquare[] =
    "# a 10 m room\n"
    "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
    "CORNER 0 0 0\nCORNER 1 10 0 10.05 0.02\nCORNER 2 10 10\nCORNER 3 0 10\n"
    "OBJECT 5 5 0.5\nOBJECT 9.8 0.2 1.5 1\nPERSON 1 1 2 2 3 0.5\n"
    "PATH 1 1\nPATH 9 1\nPATH 9 9\n";

std::string errorOf(const std::string& text) {
  std::istringstream in(text);
  try {
    readFloorPlan(in, "room.plan", 0.1, 1);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// One format for both experiments: MOSS' records (WORLD, START, ROUTE) in a
// floor plan are read and left to MOSS; the plan is the same as without them.
TEST(FloorPlan, AFileWithMossRecordsLoads) {
  std::istringstream plain_in(kSquare);
  const FloorPlan plain = readFloorPlan(plain_in, "room.plan", 0.1, 7);
  std::istringstream both_in(std::string("WORLD ROOM\nSTART 1 1 0\nROUTE 9 1\n") + kSquare);
  const FloorPlan both = readFloorPlan(both_in, "room.plan", 0.1, 7);
  ASSERT_EQ(both.walls.size(), plain.walls.size());
  ASSERT_EQ(both.corners.size(), plain.corners.size());
  for (std::size_t i = 0; i < plain.corners.size(); ++i) {
    EXPECT_EQ(both.corners[i].truth, plain.corners[i].truth);
    EXPECT_EQ(both.corners[i].label, plain.corners[i].label);
  }
  EXPECT_EQ(both.path, plain.path);
  EXPECT_EQ(both.objects.size(), plain.objects.size());
  EXPECT_EQ(both.people.size(), plain.people.size());
  // The records keep their lines, three further down.
  EXPECT_EQ(both.lines.corners[0], plain.lines.corners[0] + 3);
}

TEST(FloorPlan, ReadsEveryRecordAndLabelsUnlabelledCorners) {
  std::istringstream in(kSquare);
  const FloorPlan plan = readFloorPlan(in, "room.plan", 0.1, 7);
  ASSERT_EQ(plan.walls.size(), 4u);
  ASSERT_EQ(plan.corners.size(), 4u);
  EXPECT_EQ(plan.corners[1].label, Point2(10.05, 0.02));    // given
  EXPECT_NE(plan.corners[0].label, plan.corners[0].truth);  // drawn
  EXPECT_LT((plan.corners[0].label - plan.corners[0].truth).norm(), 0.6);
  ASSERT_EQ(plan.objects.size(), 2u);
  EXPECT_EQ(plan.objects[1].hides, 1);
  ASSERT_EQ(plan.people.size(), 1u);
  Point2 p;
  EXPECT_FALSE(plan.people[0].at(2.9, &p));
  ASSERT_TRUE(plan.people[0].at(3.0 + std::sqrt(2.0), &p));  // half way
  EXPECT_NEAR((p - Point2(1.5, 1.5)).norm(), 0, 1e-12);
  EXPECT_DOUBLE_EQ(plan.pathLength(), 16.0);
}

TEST(FloorPlan, WriteThenReadGivesTheSamePlan) {
  const FloorPlan office = builtinWorld("office", 0.1, 3);
  std::ostringstream out;
  writeFloorPlan(out, office);
  std::istringstream in(out.str());
  const FloorPlan back = readFloorPlan(in, "office.plan", 0.1, 99);
  ASSERT_EQ(back.corners.size(), office.corners.size());
  for (std::size_t i = 0; i < office.corners.size(); ++i) {
    EXPECT_EQ(back.corners[i].truth, office.corners[i].truth);
    EXPECT_EQ(back.corners[i].label, office.corners[i].label);  // labels are kept, not redrawn
  }
  EXPECT_EQ(back.walls.size(), office.walls.size());
  EXPECT_EQ(back.objects.size(), office.objects.size());
  EXPECT_EQ(back.people.size(), office.people.size());
  EXPECT_EQ(back.path, office.path);
}

TEST(FloorPlan, BuiltInWorldsAreTheThesisOnes) {
  const FloorPlan office = builtinWorld("office", 0.1, 1);
  EXPECT_NEAR(office.pathLength(), 180.0, 1e-9);  // fig. 4.1: a 180 m figure 8
  EXPECT_EQ(office.path.front(), office.path.back());
  EXPECT_GT(office.corners.size(), 100u);
  const FloorPlan corridor = builtinWorld("corridor", 0.1, 1);
  EXPECT_LT(corridor.corners.size(), 20u);  // few corners: FLAG coasts
  // Labels are off by the label noise: the sample sigma of 156 corners.
  double sum2 = 0;
  for (const Corner& c : office.corners) sum2 += (c.label - c.truth).squaredNorm();
  EXPECT_NEAR(std::sqrt(sum2 / (2.0 * office.corners.size())), 0.1, 0.02);
  // No two corners inside one association gate: the worlds test FLAG, not aliasing.
  for (std::size_t i = 0; i < office.corners.size(); ++i)
    for (std::size_t j = i + 1; j < office.corners.size(); ++j)
      EXPECT_GT((office.corners[i].truth - office.corners[j].truth).norm(), 0.5);
  EXPECT_THROW(builtinWorld("mall", 0.1, 1), Error);
}

TEST(FloorPlan, BadInputNamesFileLineAndReason) {
  EXPECT_EQ(errorOf("WALL 0 0 1\n"),
            "room.plan:1: WALL line is truncated: it has 3 fields, y2 is missing");
  EXPECT_NE(errorOf("WALL 0 0 10 0\nCORNER 0 0 zero\n").find("room.plan:2:"), std::string::npos);
  EXPECT_NE(errorOf("WALL 0 0 10 0\nDOOR 1 2\n").find("room.plan:2: unknown record 'DOOR'"),
            std::string::npos);
  EXPECT_NE(errorOf("WALL 0 0 10 0\nWALL 0 0 10 0 5\n").find("room.plan:2:"), std::string::npos);
  EXPECT_NE(errorOf("WALL 1 1 1 1\n").find("room.plan:1: zero-length wall"), std::string::npos);
  EXPECT_NE(errorOf("WALL 0 0 10 0\nPATH 1 0.5\nPATH 2 0.5\nOBJECT 1 1 -2\n")
                .find("room.plan:4: height must be >= 0"),
            std::string::npos);
  EXPECT_NE(errorOf("WALL 0 0 10 0\nPERSON 0 0 1 1 0 0\n").find("room.plan:2: speed"),
            std::string::npos);
  EXPECT_NE(errorOf("WALL 0 0 10 0\nCORNER 1 0 0\nCORNER 1 10 0\n")
                .find("room.plan:3: corner 1 is defined twice"),
            std::string::npos);
}

TEST(FloorPlan, RefusesPlansFlagCannotUse) {
  const std::string walls = "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n";
  const std::string path = "PATH 1 1\nPATH 9 1\n";
  EXPECT_NE(errorOf(walls + path).find("room.plan: the floor plan has no corners"),
            std::string::npos);
  EXPECT_NE(errorOf(walls + "CORNER 0 5 5\n" + path).find("corner 0 at (5, 5) lies on no wall"),
            std::string::npos);
  EXPECT_NE(errorOf(walls + "CORNER 0 0 0\nPATH 1 1\nPATH 12 1\n")
                .find("waypoint 1 at (12, 1) leaves the world"),
            std::string::npos);
  EXPECT_NE(errorOf(walls + "WALL 5 0 5 8\nCORNER 0 0 0\n" + path)
                .find("the path from waypoint 0 to 1 goes through the wall (5, 0)-(5, 8)"),
            std::string::npos);
  EXPECT_NE(errorOf(walls + "CORNER 0 0 0\nPATH 1 1\n").find("at least two waypoints"),
            std::string::npos);
  EXPECT_NE(errorOf(walls + "CORNER 0 0 0\nOBJECT 1 1 2 7\n" + path).find("corner 7"),
            std::string::npos);
  EXPECT_NE(errorOf("").find("no walls"), std::string::npos);
  EXPECT_THROW(readFloorPlanFile("/nonexistent/world.plan", 0.1, 1), Error);
}

// Each plan FLAG cannot use, named by the line of
// the record at fault: the corner, the object, the waypoint (and the wall it
// crosses). Only what no one line causes is named by the file alone.
TEST(FloorPlan, RefusalsNameTheLineOfTheRecordAtFault) {
  const std::string walls =
      "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n";  // lines 1-4
  const std::string path = "PATH 1 1\nPATH 9 1\n";
  EXPECT_EQ(errorOf(walls + path), "room.plan: the floor plan has no corners (landmarks)");
  EXPECT_EQ(errorOf(walls + "CORNER 0 0 0\nCORNER 1 5 5\n" + path),
            "room.plan:6: corner 1 at (5, 5) lies on no wall (nearest is 5 m away)");
  EXPECT_EQ(errorOf(walls + "CORNER 0 0 0\nPATH 1 1\nPATH 9 1\nPATH 12 1\n"),
            "room.plan:8: waypoint 2 at (12, 1) leaves the world (the walls span (0, 0)-(10, "
            "10))");
  EXPECT_EQ(errorOf(walls + "CORNER 0 0 0\nPATH 1 1\nPATH 1 -3\n"),
            "room.plan:7: waypoint 1 at (1, -3) leaves the world (the walls span (0, 0)-(10, "
            "10))");
  EXPECT_EQ(errorOf(walls + "WALL 5 0 5 8\nCORNER 0 0 0\n" + path),
            "room.plan:8: the path from waypoint 0 to 1 goes through the wall (5, 0)-(5, 8) of "
            "line 5");
  EXPECT_EQ(errorOf(walls + "CORNER 0 0 0\nOBJECT 1 1 2 7\n" + path),
            "room.plan:6: an object hides corner 7, which does not exist");
  EXPECT_EQ(errorOf(walls + "CORNER 0 0 0\nPATH 1 1\n"),
            "room.plan: the path needs at least two waypoints");
  // A built plan has no lines: its name alone.
  FloorPlan built = builtinWorld("corridor", 0.1, 1);
  built.path.push_back(Point2(1e3, 0));
  try {
    built.validate("corridor");
    ADD_FAILURE() << "a waypoint 1 km away was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("corridor: waypoint", 0), 0u) << e.what();
  }
}

TEST(FloorPlan, NegativeNoiseAndGateAreRefused) {
  std::istringstream in(kSquare);
  EXPECT_THROW(readFloorPlan(in, "room.plan", -0.1, 1), Error);
  EXPECT_THROW(builtinWorld("office", -1, 1), Error);
  SimulatorOptions sim;
  sim.noise.range_sigma = -0.05;
  EXPECT_THROW(sim.validate(), Error);
  sim = SimulatorOptions();
  sim.noise.odom_sigma_theta = -1;
  EXPECT_THROW(sim.validate(), Error);
  FlagOptions o;
  o.association.gate = -0.5;
  EXPECT_THROW(o.validate(), Error);
  o = FlagOptions();
  o.consistency.threshold = 0;
  EXPECT_THROW(o.validate(), Error);
  o = FlagOptions();
  o.landmarks.sigma = -0.1;
  EXPECT_THROW(o.validate(), Error);
  o = FlagOptions();
  o.max_mixture.null_weight = 1.5;
  EXPECT_THROW(o.validate(), Error);
  EXPECT_NO_THROW(FlagOptions().validate());
}

}  // namespace
}  // namespace hamal::flag
