// The built-in floor plans (builtin_worlds.h; thesis sec. 4.4.2, fig. 4.1).
#include "apps/flag/builtin_worlds.h"

#include <cmath>
#include <fstream>
#include <random>

#include "apps/common/builtin_name.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

// Builds closed polygons whose every vertex is a labelled corner.
class PlanBuilder {
 public:
  explicit PlanBuilder(FloorPlan* plan) : plan_(plan) {}

  // A rectangle [x0,x1]x[y0,y1], walked counter-clockwise, with niches of
  // `width` x `depth` every `spacing` metres along each side. `into_left` puts
  // the niche on the left of the walking direction (into a block seen from
  // the corridor around it) or on its right (out of a building's shell).
  void rectangle(double x0, double y0, double x1, double y1, double spacing, double width,
                 double depth, bool into_left) {
    const Point2 v[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    std::vector<Point2> poly;
    for (int s = 0; s < 4; ++s) {
      const Point2 a = v[s], b = v[(s + 1) % 4];
      const double len = (b - a).norm();
      const Point2 d = (b - a) / len;
      const Point2 left(-d.y(), d.x());
      const Point2 n = into_left ? left : Point2(-left);
      poly.push_back(a);
      if (spacing <= 0) continue;
      for (double s0 = spacing; s0 + width < len - 1.5; s0 += spacing) {
        poly.push_back(a + d * s0);
        poly.push_back(a + d * s0 + n * depth);
        poly.push_back(a + d * (s0 + width) + n * depth);
        poly.push_back(a + d * (s0 + width));
      }
    }
    for (std::size_t i = 0; i < poly.size(); ++i) {
      plan_->walls.push_back({poly[i], poly[(i + 1) % poly.size()]});
      Corner c;
      c.id = plan_->corners.size();
      c.truth = c.label = poly[i];
      plan_->corners.push_back(c);
    }
  }

 private:
  FloorPlan* plan_;
};

void labelCorners(FloorPlan* plan, double label_sigma, std::uint64_t seed) {
  if (!(label_sigma >= 0) || !std::isfinite(label_sigma))
    throw Error("label sigma must be >= 0 and finite");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (Corner& c : plan->corners) {
    const double dx = noise(rng), dy = noise(rng);
    c.label = c.truth + label_sigma * Point2(dx, dy);
  }
}

// 48 m x 24 m, two 21 m x 20 m blocks, 2 m corridors; the figure 8 along the
// corridors' centre lines is 4 x 23 + 4 x 22 = 180 m.
FloorPlan office() {
  FloorPlan plan;
  plan.name = "office";
  PlanBuilder b(&plan);
  b.rectangle(0, 0, 48, 24, 9.0, 1.5, 0.7, false);  // the shell, with recesses
  b.rectangle(2, 2, 23, 22, 5.0, 1.2, 0.6, true);   // west block, door niches
  b.rectangle(25, 2, 46, 22, 5.0, 1.2, 0.6, true);  // east block
  plan.path = {{24, 1}, {47, 1}, {47, 23}, {24, 23}, {24, 1}, {1, 1}, {1, 23}, {24, 23}, {24, 1}};
  // Furniture: short boxes the detector discards, tall cabinets it does not.
  plan.objects = {{{10, 0.4}, 0.8, -1},  {{10.6, 0.4}, 0.8, -1},  {{35, 23.5}, 0.6, -1},
                  {{47.5, 12}, 1.8, -1}, {{47.5, 12.6}, 1.8, -1}, {{0.5, 8}, 1.9, -1}};
  // A cabinet standing 30 cm in front of the east block's south-east corner (fig. 4.9).
  const Point2 hidden(46, 2);
  for (const Corner& c : plan.corners)
    if ((c.truth - hidden).norm() < 1e-9)
      plan.objects.push_back({hidden + Point2(0.2, -0.22), 1.7, static_cast<std::int64_t>(c.id)});
  // People walking across the corridors past corners (fig. 4.7), timed to
  // meet the robot (2 m/s) on its first lap.
  plan.people = {{{22.6, 0.3}, {22.6, 1.8}, 44.0, 0.5},
                 {{45.5, 22.2}, {47.6, 22.2}, 22.0, 0.8},
                 {{25.3, 12.0}, {23.2, 12.5}, 38.0, 0.6},
                 {{0.4, 12.0}, {1.8, 12.5}, 61.0, 0.4}};
  return plan;
}

// 100 m x 2 m; corners at the two ends and at three niches (3 m wide, 1 m
// deep, so their corners are far apart compared with the gate) 25 m apart,
// on alternating sides.
FloorPlan corridor() {
  FloorPlan plan;
  plan.name = "corridor";
  const std::vector<Point2> poly = {{0, 0},   {25, 0},  {25, -1}, {28, -1}, {28, 0},  {75, 0},
                                    {75, -1}, {78, -1}, {78, 0},  {100, 0}, {100, 2}, {53, 2},
                                    {53, 3},  {50, 3},  {50, 2},  {0, 2}};
  for (std::size_t i = 0; i < poly.size(); ++i) {
    plan.walls.push_back({poly[i], poly[(i + 1) % poly.size()]});
    Corner c;
    c.id = i;
    c.truth = c.label = poly[i];
    plan.corners.push_back(c);
  }
  plan.path = {{1, 1}, {99, 1}, {1, 1.2}};
  plan.objects = {{{50, 0.3}, 0.9, -1}, {{60, 1.7}, 1.8, -1}};
  plan.people = {{{26.5, 0.2}, {26.5, 1.8}, 12.5, 0.5}};
  return plan;
}

}  // namespace

std::vector<std::string> builtinWorldNames() { return {"office", "corridor"}; }

FloorPlan builtinWorld(const std::string& name, double label_sigma, std::uint64_t seed) {
  FloorPlan plan;
  const std::string canonical = apps::builtinName(name, builtinWorldNames());
  if (canonical == "office") {
    plan = office();
  } else if (canonical == "corridor") {
    plan = corridor();
  } else {
    throw Error("unknown world '" + name + "' (built-in: office, corridor; or a floor-plan file)");
  }
  labelCorners(&plan, label_sigma, seed);
  plan.validate(canonical);
  return plan;
}

FloorPlan loadWorld(const std::string& name_or_file, double label_sigma, std::uint64_t seed) {
  std::string names;
  for (const std::string& n : builtinWorldNames()) {
    if (n == apps::lowerCase(name_or_file)) return builtinWorld(n, label_sigma, seed);
    names += (names.empty() ? "" : ", ") + n;
  }
  if (!std::ifstream(name_or_file))
    throw Error(name_or_file + ": neither a built-in world (" + names +
                ") nor a floor-plan file that can be opened");
  return readFloorPlanFile(name_or_file, label_sigma, seed);
}

}  // namespace hamal::flag
