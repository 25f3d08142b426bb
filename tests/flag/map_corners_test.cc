// The map's corners from its wall segments (map_corners.h): pieces of one
// wall seen from several scans merge into one wall, two walls meeting at
// their ends make one corner where their lines meet, so does a wall ending
// at another's side (a T), a wall seen too seldom makes none, and options
// out of range are refused by name.
#include "apps/flag/map_corners.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace hamal::flag {
namespace {

// `n` noisy-free pieces of the wall from a to b, each a different 80% of it.
void addPieces(std::vector<WallSegment>* out, Point2 a, Point2 b, int n) {
  for (int k = 0; k < n; ++k) {
    const double s = 0.2 * k / n, e = s + 0.8;
    out->push_back({a + s * (b - a), a + e * (b - a)});
  }
}

TEST(MapCorners, AnLMakesOneCornerWhereItsWallsMeet) {
  MapCornerOptions o;
  std::vector<WallSegment> segments;
  // Walls from (0,0) to (4,0) and (4,0) to (4,3), seen up to 4 cm short of the corner.
  addPieces(&segments, {0, 0}, {3.96, 0}, 8);
  addPieces(&segments, {4, 0.04}, {4, 3}, 8);
  const std::vector<MapWall> walls = mergeWalls(segments, o);
  ASSERT_EQ(walls.size(), 2u);
  EXPECT_EQ(walls[0].segments, 8);
  const std::vector<Point2> corners = wallCorners(walls, o);
  ASSERT_EQ(corners.size(), 1u);
  EXPECT_NEAR(corners[0].x(), 4.0, 1e-6);
  EXPECT_NEAR(corners[0].y(), 0.0, 1e-6);
}

TEST(MapCorners, ATMakesACornerARareWallNone) {
  MapCornerOptions o;
  std::vector<WallSegment> segments;
  addPieces(&segments, {0, 0}, {8, 0}, 8);     // runs on past x = 4
  addPieces(&segments, {4, 0.05}, {4, 3}, 8);  // meets it in the middle
  const std::vector<Point2> t = wallCorners(mergeWalls(segments, o), o);
  ASSERT_EQ(t.size(), 1u);  // the concave corners either side of the stem
  EXPECT_NEAR(t[0].x(), 4.0, 1e-6);
  EXPECT_NEAR(t[0].y(), 0.0, 1e-6);
  o.junctions = false;
  EXPECT_TRUE(wallCorners(mergeWalls(segments, o), o).empty());
  o.junctions = true;
  segments.clear();
  addPieces(&segments, {0, 0}, {8, 0}, 8);
  addPieces(&segments, {4, 0.5}, {4, 3}, 8);  // stops 0.5 m short: no junction
  EXPECT_TRUE(wallCorners(mergeWalls(segments, o), o).empty());
  segments.clear();
  addPieces(&segments, {0, 0}, {3.96, 0}, 8);
  addPieces(&segments, {4, 0.04}, {4, 3}, o.min_segments - 1);  // seen too seldom
  EXPECT_EQ(mergeWalls(segments, o).size(), 1u);
  EXPECT_TRUE(wallCorners(mergeWalls(segments, o), o).empty());
}

TEST(MapCorners, RefusesOptionsOutOfRange) {
  MapCornerOptions o;
  o.corner_tolerance = -1;
  EXPECT_THROW(o.validate(), Error);
  o = MapCornerOptions();
  o.max_corner_angle = o.min_corner_angle / 2;
  try {
    o.validate();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("map corner angles"), std::string::npos);
  }
  o = MapCornerOptions();
  o.min_segments = 0;
  EXPECT_THROW(mergeWalls({}, o), Error);
}

}  // namespace
}  // namespace hamal::flag
