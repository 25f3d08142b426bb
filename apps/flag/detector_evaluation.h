// DetectorEvaluation: the vertical-edge detector (vertical_edge_detector.h)
// judged on real scans against a labelled set made without it (thesis sec.
// 4.3.2's perception, graded as apps/flag/README.md's real-log section says).
//
// The labels of a scan: the map's corners (map_corners.h: the walls merged
// from the line segments of every key scan at its reference pose, L and T
// corners of those walls; the detector's corner step plays no part) that
// its sensor can see from the scan's reference pose: within `max_range`,
// inside the scan's field of view, and in line of sight: the scan's own
// beams reach it: one of the three beams nearest its bearing returns from
// at least its range - `occlusion_margin` (what the map does not hold,
// people, furniture, a closed door, stands in front otherwise; a no-return
// beam reaches nothing), and unless the nearest one does (it passed where
// a map wall may be drawn: the scan, not the map, saw what is there), the
// ray from the sensor to the corner crosses no map wall farther than
// `occlusion_margin` from the corner (the corner's own walls end near it;
// a wall ending within `wall_end_radius` of it is cut there, for it and its
// walls' points: the extent past the corner is the scatter of its
// segments' ends, no wall to hide the other wall behind). The raw ranges,
// not the detector, decide this.
// And `walls_seen` of its walls show (below), two only when they meet at
// `min_wall_angle` or more: a corner seen with one wall shows as a wall's
// end, which the real logs' detector does not report (no silhouette edges).
// Only detections within `max_range` of the sensor are graded, as only
// corners there are labelled: one farther is neither right nor wrong.
// A detection is a true positive when it lies within `radius` (0.3 m) of a
// labelled corner in the world (through the reference pose), each label
// matched at most once (closest pairs first). Labels closer than `radius`
// to each other (directly or through others) are one corner, found when
// any of them is matched: the map's walls mapped twice a little apart make
// two corners of one, which no detector can report twice. precision = true
// positives / detections, recall = corners found / corners.
//
// The detector's judge is the whole log's labels (`whole_log`): the map
// part's miss what only the held-out part saw, and a real corner found
// there is no error of the detector's; the map part's figure is what FLAG,
// whose landmarks they are, can use.
#pragma once
#include <cstddef>
#include <ostream>
#include <vector>

#include "apps/carmen/carmen_log.h"
#include "apps/flag/carmen_recording.h"
#include "apps/flag/map_corners.h"
#include "apps/flag/vertical_edge_detector.h"

namespace hamal::flag {

struct DetectorEvaluationOptions {
  double radius = 0.30;            // m, a detection's distance to its label
  double max_range = 10.0;         // m, the labels' range from the sensor
  double occlusion_margin = 0.20;  // m, a wall crossing nearer the corner does not hide it
  // A corner's walls: the map walls with an end within wall_end_radius of
  // it; a wall shows when its point `arm` from the corner is seen as the
  // corner is. A label shows `walls_seen` of them (2: both walls, what a
  // corner of two lines needs; 1: one wall, a silhouette edge too).
  double wall_end_radius = 0.20;  // m (the map's corners are within 0.15 m of both walls' ends)
  double arm = 0.30;              // m (the detector's shortest segment)
  int walls_seen = 2;
  double min_wall_angle = 45 * 3.14159265358979323846 / 180;  // rad, two walls, not one
  // And a wall shows in the scan's returns: at least `wall_returns` of them
  // lie within `on_wall` of it between `arm` / 2 and `wall_extent` from
  // the corner, or farther when the beams' spacing on the wall puts fewer
  // there: as far as the ray wall_returns beams past the one at arm / 2
  // meets the wall's line, the whole wall if it never does (a wall seen at
  // a small angle to the beams, their spacing growing along it; the raw
  // ranges, not the detector, say the wall was seen there, not merely not
  // hidden; 0: not asked). A return ahead along another wall ending at the
  // corner, at min_wall_angle or more, and nearer that wall's line counts
  // for that wall only (an oblique corner's walls share the band near it).
  int wall_returns = 3;
  double wall_extent = 1.0;  // m
  // A scan is "mapped" when at least `mapped_share` of its returns within
  // max_range lie within `on_wall` of a map wall: the map holds what it
  // sees, so a detection off the labels there is the detector's error, not
  // the map's gap.
  double on_wall = 0.20;  // m
  double mapped_share = 0.8;
  void validate() const;  // throws hamal::Error naming the option
};

// labels, matched_labels: corners (labels closer than the radius are one).
struct DetectorScore {
  std::size_t scans = 0, detections = 0, true_positives = 0, labels = 0, matched_labels = 0;
  double precision() const { return detections ? double(true_positives) / detections : 1.0; }
  double recall() const { return labels ? double(matched_labels) / labels : 1.0; }
  DetectorScore& operator+=(const DetectorScore& o);
};

// The labels of a scan taken from `sensor` (world pose of the laser) with
// `scan`'s field of view: indices into `corners`.
std::vector<std::size_t> visibleMapCorners(const std::vector<Point2>& corners,
                                           const std::vector<MapWall>& walls, const Pose2& sensor,
                                           const RangeScan& scan,
                                           const DetectorEvaluationOptions& options);

// Detections (sensor frame) against the labels (world) of one scan.
DetectorScore scoreScan(const std::vector<VerticalEdge>& detections, const Pose2& sensor,
                        const std::vector<Point2>& corners, const std::vector<std::size_t>& labels,
                        const DetectorEvaluationOptions& options);

// The share of the scan's returns within max_range that lie within
// `on_wall` of a map wall (0 for a scan without such returns).
double mapCoverage(const RangeScan& scan, const Pose2& sensor, const std::vector<MapWall>& walls,
                   const DetectorEvaluationOptions& options);

// The detector with `edges` on every held-out key scan of a log prepared
// with map_corners (cf.scans.held_out, cf.walls, cf.landmarks), its corners
// those of cf.stable_edges's check (stable_edge_filter.h) as FLAG's were, each
// judged at its reference pose and the laser's offset; `mapped`, if given,
// sums the mapped scans only. With `whole_log` the labels and walls are
// the whole log's (cf.log_walls, cf.log_corners): the map part's cover only
// what the first part of the log saw, and a detection elsewhere counts as
// false there whatever it is.
DetectorScore evaluateDetectorOnLog(const carmen::CarmenLog& log, const CarmenFlag& cf,
                                    const VerticalEdgeDetectorOptions& edges,
                                    const DetectorEvaluationOptions& options,
                                    DetectorScore* mapped = nullptr, bool whole_log = false);

// For looking at the detector's errors (hamal_flag carmen
// --detector_dump): one CSV row per detection and per missed corner of the
// held-out key scans, judged as evaluateDetectorOnLog judges them, with
// what the detection's walls looked like and the error's likely cause, the
// first that applies: a false detection is
//   unlabelled_corner  within `radius` of a judge's corner that is not a
//                      label of the scan (out of sight, one wall seen),
//   unmapped_corner    within `radius` of a corner of the whole log's map
//                      (the map part never saw it; with the map part's labels),
//   clutter            farther than `on_wall` from every wall of the whole
//                      log's map (people, furniture, glass's echoes),
//   no_return          a wall's outer end next (2 beams) to a no-return beam,
//   jump_edge          a wall's outer end at a breakpoint: cut by something
//                      nearer or ending in front of something farther,
//   along_beam         a wall within 15 degrees of the beam (a jump's
//                      mixed returns, a wall seen grazing),
//   short_wall         a wall shorter than 0.5 m,
//   no_map_corner      on the map's walls where the map makes no corner
//                      (the label missing or the detection wrong);
// a missed label is `displaced` (a detection within twice `radius`) or
// `missed`.
void dumpDetectorErrors(const carmen::CarmenLog& log, const CarmenFlag& cf,
                        const VerticalEdgeDetectorOptions& edges,
                        const DetectorEvaluationOptions& options, bool whole_log,
                        std::ostream& out);

}  // namespace hamal::flag
