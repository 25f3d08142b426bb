// ManhattanWorld: see manhattan_world.h.
#include "apps/generator/manhattan_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/error.h"
#include "factors/between_factor.h"

namespace hamal::apps {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform and normal samples with a fixed algorithm (see the header).
class Sampler {
 public:
  explicit Sampler(std::uint64_t seed) : engine_(seed) {}

  // In [0, 1), from the top 53 bits.
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }
  // Below n (n > 0); the bias of the modulo is below 2^-50 for small n.
  std::size_t below(std::size_t n) { return std::size_t(engine_() % n); }
  // Standard normal by Box-Muller, both values of a pair used in turn.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]: log is finite
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Headings 0..3: east, north, west, south.
constexpr int kStepX[4] = {1, 0, -1, 0};
constexpr int kStepY[4] = {0, 1, 0, -1};

struct GridPoint {
  std::int64_t x, y;
  int heading;
};

Pose2 truePose(const GridPoint& p) {
  return {double(p.x), double(p.y), wrapAngle(p.heading * kPi / 2.0)};
}

// Spatial hash of pose indices by square cell, for the loop-closure search.
class CellIndex {
 public:
  explicit CellIndex(double cell) : cell_(cell) {}
  void add(double x, double y, std::uint32_t pose) {
    cells_[key(cellOf(x), cellOf(y))].push_back(pose);
  }
  template <typename F>
  void forNeighbours(double x, double y, F&& visit) const {
    const std::int64_t cx = cellOf(x), cy = cellOf(y);
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        auto it = cells_.find(key(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (std::uint32_t pose : it->second) visit(pose);
      }
  }

 private:
  std::int64_t cellOf(double v) const { return std::int64_t(std::floor(v / cell_)); }
  static std::uint64_t key(std::int64_t cx, std::int64_t cy) {
    return (std::uint64_t(cx) << 32) ^ (std::uint64_t(cy) & 0xffffffffu);
  }
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
};

void check(const ManhattanWorldOptions& o) {
  auto fail = [](const std::string& why) { throw Error("Manhattan world: " + why); };
  if (o.poses < 2) fail("needs at least 2 poses, got " + std::to_string(o.poses));
  if (o.poses > std::size_t(std::numeric_limits<std::uint32_t>::max()))
    fail("at most 2^32-1 poses");
  if (!(o.noise.sigma_xy > 0.0) || !std::isfinite(o.noise.sigma_xy))
    fail("sigma_xy must be positive, got " + std::to_string(o.noise.sigma_xy));
  if (!(o.noise.sigma_theta > 0.0) || !std::isfinite(o.noise.sigma_theta))
    fail("sigma_theta must be positive, got " + std::to_string(o.noise.sigma_theta));
  if (!(o.loop_closures.rate >= 0.0 && o.loop_closures.rate <= 1.0))
    fail("loop_closure_rate must be in [0, 1], got " + std::to_string(o.loop_closures.rate));
  if (!(o.loop_closures.radius >= 0.0) || !std::isfinite(o.loop_closures.radius))
    fail("loop_closure_radius must be >= 0, got " + std::to_string(o.loop_closures.radius));
  if (!(o.turn_probability >= 0.0 && o.turn_probability <= 1.0))
    fail("turn_probability must be in [0, 1], got " + std::to_string(o.turn_probability));
  if (o.world_size == 1) fail("world_size must be 0 (automatic) or at least 2");
  if (!(o.loop_closures.pose_probability >= 0.0 && o.loop_closures.pose_probability <= 1.0))
    fail("pose_closure_probability must be in [0, 1], got " +
         std::to_string(o.loop_closures.pose_probability));
  if (!(o.noise.odometry_sigma_xy >= 0.0) || !std::isfinite(o.noise.odometry_sigma_xy))
    fail("odometry_sigma_xy must be >= 0 (0: sigma_xy), got " +
         std::to_string(o.noise.odometry_sigma_xy));
  if (!(o.noise.odometry_sigma_theta >= 0.0) || !std::isfinite(o.noise.odometry_sigma_theta))
    fail("odometry_sigma_theta must be >= 0 (0: sigma_theta), got " +
         std::to_string(o.noise.odometry_sigma_theta));
  if (o.components < 1) fail("components must be at least 1");
  if (o.poses / o.components < 4)
    fail("components of at least 4 poses: " + std::to_string(o.poses) + " poses cannot make " +
         std::to_string(o.components));
}

// The first pose of each of the `components` runs of consecutive ids.
std::vector<std::size_t> componentStarts(std::size_t n, std::size_t components) {
  std::vector<std::size_t> starts;
  for (std::size_t c = 0; c < components; ++c) starts.push_back(c * n / components);
  return starts;
}

// Gap k at pose (k + 1) n / (gaps + 1), moved to 2 poses into its component
// when nearer its start (pose g is joined to g - 2 across the gap); gaps at
// least 2 apart, else an error.
std::vector<std::size_t> gapPoses(std::size_t n, std::size_t gaps,
                                  const std::vector<std::size_t>& starts) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < gaps; ++k) {
    std::size_t g = (k + 1) * n / (gaps + 1);
    const std::size_t start = *(std::upper_bound(starts.begin(), starts.end(), g) - 1);
    const std::size_t end = std::upper_bound(starts.begin(), starts.end(), g) == starts.end()
                                ? n
                                : *std::upper_bound(starts.begin(), starts.end(), g);
    if (g < start + 2) g = start + 2;
    if (g >= end || (!out.empty() && g < out.back() + 2))
      throw Error("Manhattan world: no room for " + std::to_string(gaps) +
                  " odometry gaps at least 2 poses apart and 2 poses into their component in " +
                  std::to_string(n) + " poses");
    out.push_back(g);
  }
  return out;
}

}  // namespace

ManhattanWorld generateManhattanWorld(const ManhattanWorldOptions& options) {
  check(options);
  ManhattanWorld world;
  const std::size_t n = options.poses;
  world.world_size = options.world_size
                         ? options.world_size
                         : std::max<std::size_t>(4, std::size_t(std::ceil(std::sqrt(double(n)))));
  // The world is [-half, side - half]^2 with pose 0 at the origin facing east.
  const std::int64_t low = -std::int64_t(world.world_size / 2);
  const std::int64_t high = low + std::int64_t(world.world_size);
  auto inside = [&](std::int64_t x, std::int64_t y) {
    return x >= low && x <= high && y >= low && y <= high;
  };

  Sampler sampler(options.seed);
  auto informationOf = [](double sigma_xy, double sigma_theta) {
    Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
    information(0, 0) = information(1, 1) = 1.0 / (sigma_xy * sigma_xy);
    information(2, 2) = 1.0 / (sigma_theta * sigma_theta);
    return information;
  };
  const double odometry_xy = options.noise.odometry_sigma_xy > 0 ? options.noise.odometry_sigma_xy
                                                                 : options.noise.sigma_xy;
  const double odometry_theta = options.noise.odometry_sigma_theta > 0
                                    ? options.noise.odometry_sigma_theta
                                    : options.noise.sigma_theta;
  const Eigen::Matrix3d information =
      informationOf(options.noise.sigma_xy, options.noise.sigma_theta);
  const Eigen::Matrix3d odometry_information = informationOf(odometry_xy, odometry_theta);
  auto measureWith = [&](const Pose2& a, const Pose2& b, double sigma_xy, double sigma_theta) {
    const Pose2 z = a.between(b);
    const double nx = sampler.normal() * sigma_xy;
    const double ny = sampler.normal() * sigma_xy;
    const double nth = sampler.normal() * sigma_theta;
    return Pose2(z.x + nx, z.y + ny, wrapAngle(z.theta + nth));
  };
  auto measure = [&](const Pose2& a, const Pose2& b) {
    return measureWith(a, b, options.noise.sigma_xy, options.noise.sigma_theta);
  };
  world.component_starts = componentStarts(n, options.components);
  world.gaps = gapPoses(n, options.odometry_gaps, world.component_starts);
  const bool several = options.components > 1;
  std::size_t component_start = 0, next_component = 1, next_gap = 0;

  const double radius = options.loop_closures.radius;
  const bool closures =
      (options.loop_closures.rate > 0.0 || options.loop_closures.pose_probability > 0.0) &&
      radius > 0.0;
  CellIndex index(std::max(1.0, radius));
  std::vector<Pose2> truth;
  truth.reserve(n);
  world.graph.source =
      "manhattan-world(poses=" + std::to_string(n) + ",seed=" + std::to_string(options.seed) + ")";
  world.graph.factors.reserve(n + n / 2);

  GridPoint p{0, 0, 0};
  Pose2 odometry_estimate;  // composed from the noisy odometry
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      // Straight on, or a turn to a random side; a move that would leave the
      // world takes one of the other two (one of them always stays inside).
      int turn = 0;  // +1 left, -1 right
      if (sampler.uniform() < options.turn_probability) turn = sampler.below(2) ? 1 : -1;
      int order[3] = {turn, turn == 0 ? 1 : 0, turn == 0 ? -1 : -turn};
      if (sampler.below(2)) std::swap(order[1], order[2]);
      for (int t : order) {
        const int h = (p.heading + t + 4) % 4;
        if (inside(p.x + kStepX[h], p.y + kStepY[h])) {
          p = {p.x + kStepX[h], p.y + kStepY[h], h};
          break;
        }
      }
    }
    const Pose2 pose = truePose(p);
    truth.push_back(pose);
    world.truth.insert(X(i), pose);

    if (next_component < world.component_starts.size() &&
        i == world.component_starts[next_component]) {
      // A new component: no factor to the last one, fixed at its true start.
      component_start = i;
      ++next_component;
      odometry_estimate = pose;
    } else if (next_gap < world.gaps.size() && i == world.gaps[next_gap]) {
      // An odometry gap: a loop closure from pose i - 2 across it instead.
      ++next_gap;
      const Pose2 z = measure(truth[i - 2], pose);
      world.graph.add(std::make_shared<BetweenFactor>(X(i - 2), X(i), z, information));
      odometry_estimate = world.graph.initial.pose(X(i - 2)).compose(z);
      ++world.loop_closures;
    } else if (i > 0) {
      const Pose2 z = measureWith(truth[i - 1], pose, odometry_xy, odometry_theta);
      world.graph.add(std::make_shared<BetweenFactor>(X(i - 1), X(i), z, odometry_information));
      odometry_estimate = odometry_estimate.compose(z);
      ++world.odometry_edges;
    }
    world.graph.initial.insert(X(i), odometry_estimate);
    if (several && i == component_start) world.graph.fixed.insert(X(i));

    if (closures) {
      // Candidates in index order within each cell, cells in a fixed order:
      // the same seed gives the same closures. None before
      // first_loop_closure, none to another component.
      std::vector<std::uint32_t> earlier;
      if (i >= options.loop_closures.first_pose)
        index.forNeighbours(pose.x, pose.y, [&](std::uint32_t j) {
          if (j + options.loop_closures.min_gap > i || j < component_start) return;
          const double dx = truth[j].x - pose.x, dy = truth[j].y - pose.y;
          if (dx * dx + dy * dy <= radius * radius) earlier.push_back(j);
        });
      if (options.loop_closures.pose_probability > 0) {
        // Sparse closures: at most one per pose, to a candidate drawn uniformly.
        if (!earlier.empty() && sampler.uniform() < options.loop_closures.pose_probability) {
          const std::uint32_t j = earlier[sampler.below(earlier.size())];
          earlier.assign(1, j);
        } else {
          earlier.clear();
        }
      }
      for (std::uint32_t j : earlier) {
        if (options.loop_closures.pose_probability == 0 &&
            sampler.uniform() >= options.loop_closures.rate)
          continue;
        world.graph.add(
            std::make_shared<BetweenFactor>(X(j), X(i), measure(truth[j], pose), information));
        ++world.loop_closures;
      }
      index.add(pose.x, pose.y, std::uint32_t(i));
    }
  }
  return world;
}

}  // namespace hamal::apps
