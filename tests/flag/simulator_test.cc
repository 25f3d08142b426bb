// The simulated robot and detector (apps/flag/simulator.h): deterministic
// per seed, noise that matches the stated sigmas, walls that occlude, a
// detector that discards low edges and does not see a hidden corner; the
// in-view oracle keeps exactly the corners the scan detector is graded on.
#include "apps/flag/simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "apps/flag/builtin_worlds.h"
#include "apps/flag/corner_visibility.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

TEST(Simulator, SamePlanOptionsAndSeedGiveTheSameRecording) {
  const FloorPlan plan = builtinWorld("office", 0.1, 1);
  SimulatorOptions o;
  o.seed = 5;
  const Recording a = simulate(plan, o), b = simulate(plan, o);
  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    EXPECT_EQ(a.steps[i].odometry.x, b.steps[i].odometry.x);
    ASSERT_EQ(a.steps[i].detections.size(), b.steps[i].detections.size());
    for (std::size_t k = 0; k < a.steps[i].detections.size(); ++k)
      EXPECT_EQ(a.steps[i].detections[k].range, b.steps[i].detections[k].range);
  }
  o.seed = 6;
  const Recording c = simulate(plan, o);
  EXPECT_NE(a.steps[1].odometry.x, c.steps[1].odometry.x);
}

TEST(Simulator, PosesEveryStepAlongThePathAtTheGivenSpeed) {
  const FloorPlan plan = builtinWorld("office", 0.1, 1);
  SimulatorOptions o;
  const Recording r = simulate(plan, o);
  EXPECT_EQ(r.steps.size(), 361u);               // 180 m / 0.5 m + 1
  EXPECT_NEAR(r.steps.back().time, 90.0, 1e-9);  // 180 m at 2 m/s
  for (std::size_t i = 1; i < r.steps.size(); ++i) EXPECT_NEAR(r.steps[i].distance, 0.5, 1e-9);
}

// Odometry and measurement noise, over many steps, have the stated sigmas:
// the sample standard deviation of n = 20000 normal draws is within 3% of
// sigma with probability > 0.9999 (its relative sd is 1/sqrt(2n) = 0.5%).
TEST(Simulator, NoiseMatchesTheStatedSigmas) {
  FloorPlan plan = builtinWorld("corridor", 0.1, 1);
  plan.path.clear();
  for (int k = 0; k < 101; ++k) {  // 100 legs of the corridor: 19600 steps
    plan.path.push_back(k % 2 ? Point2(99, 1) : Point2(1, 1));
  }
  SimulatorOptions o;
  o.seed = 11;
  o.detector = SimulatorOptions::kOracle;
  const Recording r = simulate(plan, o);
  double sx = 0, sy = 0, st = 0, sr = 0, sb = 0;
  std::size_t n = 0, m = 0;
  for (std::size_t i = 1; i < r.steps.size(); ++i) {
    const RecordedStep& s = r.steps[i];
    const Pose2 truth = r.steps[i - 1].truth.between(s.truth);
    sx += std::pow(s.odometry.x - truth.x, 2);
    sy += std::pow(s.odometry.y - truth.y, 2);
    st += std::pow(wrapAngle(s.odometry.theta - truth.theta), 2);
    ++n;
    const std::vector<Detection> clean = detect(plan, s.truth, s.time, o);
    ASSERT_EQ(clean.size(), s.detections.size());
    for (std::size_t k = 0; k < clean.size(); ++k) {
      sr += std::pow(s.detections[k].range - clean[k].range, 2);
      sb += std::pow(wrapAngle(s.detections[k].bearing - clean[k].bearing), 2);
      ++m;
    }
  }
  ASSERT_GT(n, 19000u);
  ASSERT_GT(m, 20000u);
  const double per_step = std::sqrt(0.5);  // sigma x sqrt(0.5 m)
  EXPECT_NEAR(std::sqrt(sx / n) / (0.10 * per_step), 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(sy / n) / (0.05 * per_step), 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(st / n) / (0.1 * kDeg * per_step), 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(sr / m) / 0.05, 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(sb / m) / (0.5 * kDeg), 1.0, 0.03);
}

// The noise the world draws and the sigmas the recording states (FLAG's
// factors) are separate: drawn twice as large as stated, the odometry's
// scatter is twice the stated sigma; the detectors' draws do not move the
// odometry, so the scan and oracle arms are paired.
TEST(Simulator, DrawnNoiseAndStatedSigmasAreSeparate) {
  FloorPlan plan = builtinWorld("corridor", 0.1, 1);
  SimulatorOptions o;
  o.seed = 4;
  o.detector = SimulatorOptions::kOracle;
  o.noise.odom_sigma_x = 0.2;
  o.noise.range_sigma = 0.1;
  o.stated.range_sigma = 0.02;
  const Recording r = simulate(plan, o);
  EXPECT_DOUBLE_EQ(r.odom_sigma_x, 0.10);  // stated, the thesis' value
  double sx = 0, sr = 0;
  std::size_t n = 0, m = 0;
  for (std::size_t i = 1; i < r.steps.size(); ++i) {
    const RecordedStep& s = r.steps[i];
    sx += std::pow(s.odometry.x - r.steps[i - 1].truth.between(s.truth).x, 2);
    ++n;
    const std::vector<Detection> clean = detect(plan, s.truth, s.time, o);
    for (std::size_t k = 0; k < clean.size(); ++k) {
      EXPECT_EQ(s.detections[k].range_sigma, 0.02);
      sr += std::pow(s.detections[k].range - clean[k].range, 2);
      ++m;
    }
  }
  EXPECT_NEAR(std::sqrt(sx / n) / (0.2 * std::sqrt(0.5)), 1.0, 0.15);
  EXPECT_NEAR(std::sqrt(sr / m) / 0.1, 1.0, 0.1);
  SimulatorOptions scan = o;
  scan.detector = SimulatorOptions::kScan;
  const Recording q = simulate(plan, scan);
  ASSERT_EQ(q.steps.size(), r.steps.size());
  for (std::size_t i = 0; i < r.steps.size(); ++i)
    ASSERT_EQ(q.steps[i].odometry.x, r.steps[i].odometry.x);
  o.stated.odom_sigma_x = 0;
  EXPECT_THROW(simulate(plan, o), Error);
}

TEST(Simulator, WallsOccludeAndTheDetectorDiscardsLowEdges) {
  std::istringstream in(
      "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
      "WALL 5 0 5 6\n"  // a partition
      "CORNER 0 0 0\nCORNER 1 10 0\nCORNER 2 5 6\nCORNER 3 0 10\n"
      "OBJECT 2 2 0.5\nOBJECT 2 3 1.5\nOBJECT 0.2 9.7 1.2 3\n"
      "PERSON 3 1 3 5 0 1\nPATH 1 1\nPATH 1 8\n");
  const FloorPlan plan = readFloorPlan(in, "room", 0.1, 1);
  SimulatorOptions o;
  o.sensor_range = 20;
  const std::vector<Detection> d = detect(plan, Pose2(1, 1, 0), 1.0, o);
  std::vector<std::string> seen;
  for (const Detection& x : d)
    seen.push_back(std::string(x.source.kind == Source::kCorner   ? "c"
                               : x.source.kind == Source::kObject ? "o"
                                                                  : "p") +
                   std::to_string(x.source.id));
  // Corner 1 is behind the partition, corner 3 behind the tall object in
  // front of it, object 0 is lower than 1 m; the person is at (3, 2).
  EXPECT_EQ(seen, (std::vector<std::string>{"c0", "c2", "o1", "o2", "p0"}));
  for (const Detection& x : d)
    if (x.source.kind == Source::kPerson) {
      EXPECT_NEAR(x.range, std::hypot(2.0, 1.0), 1e-12);
      EXPECT_NEAR(x.bearing, std::atan2(1.0, 2.0), 1e-12);
    }
  o.min_height = 0.4;  // a lower threshold sees the box
  EXPECT_EQ(detect(plan, Pose2(1, 1, 0), 1.0, o).size(), d.size() + 1);
  o.sensor_range = 1.0;  // the nearest, corner 0, is 1.41 m away
  EXPECT_TRUE(detect(plan, Pose2(1, 1, 0), 1.0, o).empty());
}

// The in-view oracle: the oracle's corner detections of corners in view
// (a wall segment and a stub), its object and person detections, nothing
// else; on the office it drops the occluding edges, about half.
TEST(Simulator, InViewOracleKeepsTheCornersInView) {
  const FloorPlan plan = builtinWorld("office", 0.1, 1);
  SimulatorOptions o;
  o.detector = SimulatorOptions::kOracle;
  const Recording all = simulate(plan, o);
  o.detector = SimulatorOptions::kOracleInView;
  const Recording in_view = simulate(plan, o);
  RangeScannerOptions scanner = o.scanner;
  scanner.max_range = o.sensor_range;
  std::size_t corners_all = 0, corners_in_view = 0;
  ASSERT_EQ(all.steps.size(), in_view.steps.size());
  for (std::size_t i = 0; i < all.steps.size(); ++i) {
    const RecordedStep &a = all.steps[i], &v = in_view.steps[i];
    const auto view = visibleCorners(plan, a.truth, a.time, scanner, o.edges.segments.min_length,
                                     o.edges.corners.min_stub_length)
                          .in_view;
    std::size_t k = 0;
    for (const Detection& d : a.detections) {
      const bool kept = d.source.kind != Source::kCorner ||
                        std::find(view.begin(), view.end(), d.source.id) != view.end();
      corners_all += d.source.kind == Source::kCorner;
      if (!kept) continue;
      ASSERT_LT(k, v.detections.size());
      EXPECT_EQ(v.detections[k].source.id, d.source.id);
      EXPECT_EQ(v.detections[k].range, d.range);  // the same noise draws
      corners_in_view += d.source.kind == Source::kCorner;
      ++k;
    }
    EXPECT_EQ(k, v.detections.size());
  }
  EXPECT_GT(corners_in_view, corners_all / 3);
  EXPECT_LT(corners_in_view, 2 * corners_all / 3);
}

}  // namespace
}  // namespace hamal::flag
