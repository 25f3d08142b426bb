// CornerVisibility: which of a floor plan's corners a scan can show as a
// corner, and which detection came from what: the ground truth the
// vertical-edge detector (vertical_edge_detector.h) is graded against
// (precision and recall, apps/flag/README.md).
//
// A corner is in view when it is within the scanner's range and line of
// sight (walls, objects and people of range_scan.h block it) and so are the
// points `wall_length` along one wall that meets at it and `stub_length`
// along the other: both of its walls show, one long enough to be a wall
// segment, the other at least a stub, so a detector that needs two lines can
// see it. A corner seen with one wall only shows, if at all, as a
// silhouette edge (vertical_edge_detector.h, step 4); `in_sight` counts
// those too: the recall against everything in line of sight is the one
// that grades silhouette edges.
#pragma once
#include <cstdint>
#include <vector>

#include "apps/flag/range_scan.h"
#include "apps/flag/simulator.h"

namespace hamal::flag {

struct VisibleCorners {
  std::vector<std::uint64_t> in_view;   // both walls show
  std::vector<std::uint64_t> in_sight;  // line of sight to the corner itself
};

VisibleCorners visibleCorners(const FloorPlan& plan, const Pose2& pose, double time,
                              const RangeScannerOptions& scanner, double wall_length,
                              double stub_length);

// What a detection at world position `p` came from: the nearest floor-plan
// corner within `radius`, else an object box's corner, else a person within
// `radius` of their circle, else nothing (Source::kNone).
Source sourceOf(const FloorPlan& plan, const Point2& p, double time,
                const RangeScannerOptions& scanner, double radius);

// A recording's detections against the corners in view at each pose:
// precision (detections from a floor-plan corner / all) and recall (corners
// in view detected / corners in view, and the same of those in sight).
struct DetectionScore {
  std::size_t detections = 0, from_corner = 0, from_object = 0, from_person = 0, from_nothing = 0;
  std::size_t in_view = 0, in_view_detected = 0, in_sight = 0, in_sight_detected = 0;
  // RMS of the corners' detections' range and bearing errors, m and rad.
  double range_rms = 0, bearing_rms = 0;
  double precision() const { return detections ? double(from_corner) / detections : 1.0; }
  double recall() const { return in_view ? double(in_view_detected) / in_view : 1.0; }
  double recallInSight() const { return in_sight ? double(in_sight_detected) / in_sight : 1.0; }
};

// In view as VisibleCorners with the detector's segments.min_length and
// corners.min_stub_length (options.edges), the least its corners are made
// of.
DetectionScore scoreDetections(const FloorPlan& plan, const Recording& recording,
                               const SimulatorOptions& options);

}  // namespace hamal::flag
