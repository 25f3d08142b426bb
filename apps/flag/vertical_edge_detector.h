// VerticalEdgeDetector: FLAG's perception (thesis sec. 4.3.2): the corners
// of a 2.5D range scan (range_scan.h) at least `min_height` tall, the
// vertical edges that a floor plan's labelled corners are. Each step's
// options are a group of VerticalEdgeDetectorOptions.
//
// 1. Breakpoints (Borges & Aldon 2004's adaptive breakpoint detector): two
//    consecutive returns are on one surface unless they are farther apart
//    than r * sin(step) / sin(lambda - step) + 3 sigma, i.e. than a surface
//    seen at less than `breakpoints.lambda` to the beam could space them. A
//    no-return beam is a breakpoint too.
// 2. Split-and-merge line extraction in each run between breakpoints:
//    split a run at its point farthest from the chord while that point is
//    more than `segments.fit_tolerance` off; then merge neighbours whose
//    union's total-least-squares line keeps every point within
//    `segments.fit_tolerance`. A segment keeps at least
//    `segments.min_points` points and `segments.min_length` metres; shorter
//    ones (people, the arcs of round things, noise at a corner) make no
//    corner.
// 3. Corners: two segments that follow each other in one run (nothing but a
//    short segment or the shared break point between them, no breakpoint)
//    whose lines meet at an angle within [corners.min_angle,
//    corners.max_angle] (0 is collinear), where the intersection is within
//    `corners.tolerance` of both segments' near ends. Convex (the edge
//    points at the sensor) and concave (a room's inside corner) alike. A
//    kept segment whose end made no corner may meet the piece adjoining it
//    there when that is a stub of at least `corners.min_stub_points` and
//    `corners.min_stub_length` (the second wall seen short: foreshortened,
//    far, or mostly hidden), with the same angle and distance tests. On real
//    scans (clutter, people, glass, noise) three more: the longer of a
//    corner's walls is at least `corners.min_long_wall` (a sawtooth of short
//    pieces is a row of chairs, a person, a shelf's contents, not a
//    building's corner), each wall fits its line within
//    `corners.max_fit_rms` RMS (a wall is flat to the range noise; an uneven
//    surface's pieces are not), and a wall shorter than
//    `corners.min_open_wall` does not end in the open at its outer end (the
//    run turns again there by a corner's least angle, or ends with the beam
//    past it returning from beyond the wall's line): so short a surface
//    that ends rather than being cut from sight (by something nearer, a
//    no-return beam, the field of view) is a door jamb's, a recess's or a
//    pillar's face, a real edge but not a plan's corner, whose walls are
//    longer (the map's shortest wall, map_corners.h, is 0.5 m).
// 4. Occluding edges: at a breakpoint where the range jumps, the far side's
//    segment end is where a surface goes on behind something nearer, never
//    a vertical edge. The near side's end is one in a world of polygons (a
//    convex corner whose second face is hidden or grazing, or a wall's
//    end): the silhouette edge a 3D lidar sees as a vertical edge too.
//    With `silhouettes.enabled` a kept segment at least
//    `silhouettes.min_length` long (longer than a person's outline or a
//    box's side fits a line) whose end is its run's end makes a convex
//    silhouette edge there when the beam past that end returns at least
//    `silhouettes.margin` beyond the segment's line extended to that beam;
//    a no-return beam counts as returning at max_range, so a wall running
//    out of range makes none, and neither does the scan's first or last
//    beam of a partial field of view (nothing is known past it). The end
//    lies somewhere between the last beam on the segment and the next one:
//    the edge is put half-way, on the fitted line at the bearing half a
//    beam past the last, within half the beams' spacing on the wall of the
//    truth; a wall seen so obliquely that they are more than
//    `silhouettes.max_spacing` apart (0.5 m: the edge within 0.25 m, half
//    the association gate) makes none.
// 5. 2.5D: an edge's height is the lowest return within `corners.tolerance`
//    + a beam of it; lower than `min_height` (thesis: 1 m) is furniture.
//
// The position is the lines' intersection (a silhouette edge: as in 4), in
// the sensor frame.
#pragma once
#include <vector>

#include "apps/flag/range_scan.h"

namespace hamal::flag {

struct VerticalEdgeDetectorOptions {
  // Step 1: where a run of returns breaks.
  struct Breakpoints {
    double lambda = 5 * 3.14159265358979323846 / 180;  // rad
    double range_sigma = 0.015;                        // m, the breakpoint's 3-sigma margin
  };
  // Step 2: the wall segments split and merge keeps.
  struct Segments {
    double fit_tolerance = 0.05;  // m, a point's largest distance from its line
    int min_points = 6;
    double min_length = 0.30;  // m
  };
  // Step 3: two walls that make a corner.
  struct Corners {
    // A corner's second wall may be a stub this short.
    int min_stub_points = 3;
    double min_stub_length = 0.15;                          // m
    double min_angle = 45 * 3.14159265358979323846 / 180;   // rad
    double max_angle = 135 * 3.14159265358979323846 / 180;  // rad
    double tolerance = 0.15;                                // m
    double min_long_wall = 0;                               // m, 0: not asked
    double max_fit_rms = 0;                                 // m, 0: not asked
    double min_open_wall = 0;                               // m, 0: not asked (step 3)
  };
  // Step 4: a segment's end at a jump away from the sensor as a vertical edge.
  struct Silhouettes {
    bool enabled = true;
    double margin = 0.2;       // m, along the beam past the end
    double min_length = 0.5;   // m
    double max_spacing = 0.5;  // m, between the beams on the wall at its end
  };
  Breakpoints breakpoints;
  Segments segments;
  Corners corners;
  Silhouettes silhouettes;
  double min_height = 1.0;  // m (thesis sec. 4.3.2)
  // Throws hamal::Error naming the option for a value out of range.
  void validate() const;
};

// The settings for real laser logs (CARMEN's 180-degree, 1-degree scans):
// Borges & Aldon's 10-degree breakpoint, both of a corner's walls full
// segments, no silhouette edges. The 5-degree breakpoint, the stub rule and
// silhouette edges were chosen on the simulated scanner; on the logs none
// made FLAG better on both Intel and ACES. Clutter's corners refused
// (corners of 75-105 degrees, the longer wall 0.8 m, walls fit within 2.5 cm
// RMS): chosen on ACES, the most precise detector against its labels
// (detector_evaluation.h) at recall >= 0.5 whose FLAG on ACES is no worse
// (2 cm RMS drops ACES's own noisy walls), judged on Intel and Freiburg 079.
// A wall under 0.5 m must not end in the open (the map's shortest wall;
// 0.5-0.6 m alike on ACES), judged on Intel and Freiburg 079.
// On a log, a corner may also be asked to be seen again from the
// neighbouring scans (stable_edge_filter.h, off by default): the rules judge
// one scan, that check what moves or vanishes between scans.
VerticalEdgeDetectorOptions realLogDetectorOptions();

struct VerticalEdge {
  Point2 position;  // sensor frame
  double range = 0, bearing = 0;
  double angle = 0;  // between the two walls' lines, rad (0: collinear or a silhouette)
  double height = 0;
  bool convex = false;
  bool silhouette = false;  // one wall seen, ending at a jump away (step 4)
  // Its walls as seen (for judging the detector, detector_evaluation.h):
  // the beams of their outer ends, their lengths (the first 0 for a
  // silhouette), the larger of their RMS distances from their lines.
  std::size_t first_beam = 0, last_beam = 0;
  double legs[2] = {0, 0};  // m
  double fit_rms = 0;       // m
  // The directions its walls leave it in, sensor frame (rad): the corner's
  // shape and orientation, a descriptor for association (FlagOptions::
  // association.wall_sigma). A corner has two, a silhouette one.
  std::vector<double> walls;
};

struct LineSegment {
  Point2 a, b;                      // ends, projected on the fitted line, in scan order
  std::size_t first = 0, last = 0;  // beam indices
};

// The segments step 2 keeps (for plots and tests).
std::vector<LineSegment> extractLineSegments(const RangeScan& scan,
                                             const VerticalEdgeDetectorOptions& options);
std::vector<VerticalEdge> detectVerticalEdges(const RangeScan& scan,
                                              const VerticalEdgeDetectorOptions& options);

}  // namespace hamal::flag
