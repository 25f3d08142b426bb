// Ground truth for the vertical-edge detector (corner_visibility.h).
#include "apps/flag/corner_visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hamal::flag {

VisibleCorners visibleCorners(const FloorPlan& plan, const Pose2& pose, double time,
                              const RangeScannerOptions& scanner, double wall_length,
                              double stub_length) {
  VisibleCorners out;
  const Point2 o = pose.t();
  const auto seen = [&](const Point2& p) {
    return (p - o).norm() < scanner.max_range && lineOfSight(plan, o, p, time, scanner);
  };
  for (const Corner& c : plan.corners) {
    if (!seen(c.truth)) continue;
    out.in_sight.push_back(c.id);
    int walls = 0, stubs = 0, long_walls = 0;
    for (const Wall& w : plan.walls) {
      Point2 other;
      if ((w.a - c.truth).norm() < 1e-6)
        other = w.b;
      else if ((w.b - c.truth).norm() < 1e-6)
        other = w.a;
      else
        continue;
      ++walls;
      const Point2 d = other - c.truth;
      const auto shows = [&](double length) {
        return seen(c.truth + d.normalized() * std::min(length, d.norm()));
      };
      if (shows(stub_length)) ++stubs;
      if (shows(wall_length)) ++long_walls;
    }
    if (walls >= 2 && stubs == walls && long_walls >= 1) out.in_view.push_back(c.id);
  }
  return out;
}

Source sourceOf(const FloorPlan& plan, const Point2& p, double time,
                const RangeScannerOptions& scanner, double radius) {
  double best = radius;
  Source s;
  s.kind = Source::kNone;
  for (const Corner& c : plan.corners) {
    const double d = (c.truth - p).norm();
    if (d <= best) {
      best = d;
      s = {Source::kCorner, c.id};
    }
  }
  if (s.kind == Source::kCorner) return s;
  for (std::size_t k = 0; k < plan.objects.size(); ++k)
    for (const Wall& w : objectBox(plan.objects[k], scanner.object_side))
      if ((w.a - p).norm() <= radius) return {Source::kObject, k};
  for (std::size_t k = 0; k < plan.people.size(); ++k) {
    Point2 at;
    if (plan.people[k].at(time, &at) && (at - p).norm() <= scanner.person_radius + radius)
      return {Source::kPerson, k};
  }
  return s;
}

DetectionScore scoreDetections(const FloorPlan& plan, const Recording& recording,
                               const SimulatorOptions& options) {
  RangeScannerOptions scanner = options.scanner;
  scanner.max_range = options.sensor_range;
  DetectionScore score;
  for (const RecordedStep& step : recording.steps) {
    std::vector<std::uint64_t> found;
    for (const Detection& d : step.detections) {
      ++score.detections;
      switch (d.source.kind) {
        case Source::kCorner: {
          ++score.from_corner;
          found.push_back(d.source.id);
          const Point2 t = step.truth.transformTo(plan.corner(d.source.id)->truth);
          score.range_rms += std::pow(d.range - t.norm(), 2);
          score.bearing_rms += std::pow(wrapAngle(d.bearing - std::atan2(t.y(), t.x())), 2);
          break;
        }
        case Source::kObject:
          ++score.from_object;
          break;
        case Source::kPerson:
          ++score.from_person;
          break;
        case Source::kNone:
          ++score.from_nothing;
          break;
      }
    }
    const auto detected = [&](std::uint64_t id) {
      return std::find(found.begin(), found.end(), id) != found.end();
    };
    const VisibleCorners v =
        visibleCorners(plan, step.truth, step.time, scanner, options.edges.segments.min_length,
                       options.edges.corners.min_stub_length);
    score.in_view += v.in_view.size();
    score.in_sight += v.in_sight.size();
    for (std::uint64_t id : v.in_view) score.in_view_detected += detected(id);
    for (std::uint64_t id : v.in_sight) score.in_sight_detected += detected(id);
  }
  if (score.from_corner) {
    score.range_rms = std::sqrt(score.range_rms / double(score.from_corner));
    score.bearing_rms = std::sqrt(score.bearing_rms / double(score.from_corner));
  }
  return score;
}

}  // namespace hamal::flag
