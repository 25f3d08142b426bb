// The one world file format (apps/common/world_file.h): every record of
// FLAG's floor plans and MOSS' worlds is read with its line, and a bad
// record is refused naming the file, the line and the reason.
#include "apps/common/world_file.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace hamal::apps {
namespace {

// A room both experiments can use: MOSS' start and route, FLAG's corners,
// object, person and path, and the walls they share.
const char kBoth[] =
    "# a 10 m room\n"
    "WORLD ROOM\n"
    "START 1 1 0\nROUTE 9 1\nROUTE 9 9\n"
    "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
    "CORNER 0 0 0\nCORNER 1 10 0 10.05 0.02\nCORNER 2 10 10\nCORNER 3 0 10\n"
    "OBJECT 5 5 0.5 1\nPERSON 1 1 2 2 3 0.5\n"
    "PATH 1 1\nPATH 9 1\nPATH 9 9\n";

TEST(WorldFile, ReadsEveryRecordWithItsLine) {
  const WorldFile w = parseWorldFile(std::string(kBoth), "room.world");
  EXPECT_EQ(w.name, "ROOM");
  EXPECT_EQ(w.lines, 18);
  ASSERT_TRUE(w.has_start);
  EXPECT_EQ(w.start_line, 3);
  EXPECT_DOUBLE_EQ(w.start.x, 1.0);
  ASSERT_EQ(w.route.size(), 2u);
  EXPECT_EQ(w.route[1].line, 5);
  ASSERT_EQ(w.walls.size(), 4u);
  EXPECT_EQ(w.walls[0].line, 6);
  EXPECT_DOUBLE_EQ(w.walls[1].a.x(), 10.0);
  ASSERT_EQ(w.corners.size(), 4u);
  EXPECT_FALSE(w.corners[0].has_label);
  EXPECT_TRUE(w.corners[1].has_label);
  EXPECT_DOUBLE_EQ(w.corners[1].label.x(), 10.05);
  ASSERT_EQ(w.objects.size(), 1u);
  EXPECT_EQ(w.objects[0].hides, 1);
  ASSERT_EQ(w.people.size(), 1u);
  EXPECT_DOUBLE_EQ(w.people[0].speed, 0.5);
  ASSERT_EQ(w.path.size(), 3u);
  EXPECT_EQ(w.path[2].line, 18);
}

TEST(WorldFile, RefusesABadRecordNamingTheLine) {
  const std::string ok = "WALL 0 0 10 0\n";
  const std::pair<std::string, std::string> cases[] = {
      {ok + "DOOR 1 2\n", "w:2: unknown record 'DOOR'"},
      {ok + "WALL 1 1 1 1\n", "w:2: zero-length wall"},
      {"START 1 1 0\nSTART 2 2 0\n", "w:2: a second START"},
      {ok + "CORNER 1 2 0\nCORNER 1 3 0\n", "w:3: corner 1 is defined twice"},
      {ok + "OBJECT 1 1 -1\n", "w:2: height must be >= 0"},
      {ok + "PERSON 1 1 2 2 0 0\n", "w:2: speed must be > 0"},
      {ok + "PATH 1\n", "w:2:"},
      {ok + "ROUTE 1 2 3\n", "w:2:"},
  };
  for (const auto& [text, expected] : cases) {
    try {
      parseWorldFile(text, "w");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
          << e.what() << " (expected " << expected << ")";
    }
  }
}

}  // namespace
}  // namespace hamal::apps
