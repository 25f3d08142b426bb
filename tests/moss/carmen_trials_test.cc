// MOSS on a real log's format (carmen_trials.h): a small CARMEN log made
// here (a robot circling a room two and a half times, FLASER ranges cast
// against the room and a pillar) is cut into a prior map (the first
// traversal) and localization trials that revisit it, training strictly
// before test; real-scan matches become L2G factors; the experiment runs on
// it end to end (both errors in its rows); bad logs and options are refused
// by name.
#include "apps/moss/carmen_trials.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "apps/moss/experiment.h"
#include "apps/moss/localizer.h"
#include "backends/builtins.h"
#include "core/error.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal::moss {
namespace {

// Distance from (x, y) along (c, s) to the box [x0, x1] x [y0, y1]: the exit
// from inside, the entry from outside (inf if missed).
double rayBox(double x, double y, double c, double s, double x0, double y0, double x1, double y1) {
  double lo = -1e300, hi = 1e300;
  for (auto [p, d, a, b] :
       {std::array<double, 4>{x, c, x0, x1}, std::array<double, 4>{y, s, y0, y1}}) {
    if (std::abs(d) < 1e-12) {
      if (p < a || p > b) return INFINITY;
      continue;
    }
    double t0 = (a - p) / d, t1 = (b - p) / d;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  if (lo > hi || hi < 0) return INFINITY;
  return lo > 0 ? lo : hi;
}

// The wheel odometry of circlingLog at pose index u (fractional between
// scans): a circle 5% too large, as a wheel radius off by 5% draws it.
Pose2 wheelOdometry(double u) {
  const double r = 3.15, a = u * 0.51 / 3.0;
  return Pose2(r * std::cos(a), r * std::sin(a), wrapAngle(a + M_PI / 2));
}

// `laps` laps of a 3 m circle in a 10 m room with a 1 m pillar off centre,
// a pose every 0.51 m (above the 0.5 m pose step), 180 beams over 180 degrees;
// ODOM records (wheelOdometry) at each scan's time and half-way to the next.
std::string circlingLog(double laps) {
  std::ostringstream os;
  const double r = 3.0, step = 0.51 / r;
  const int n = static_cast<int>(laps * 2 * M_PI / step);
  for (int i = 0; i < n; ++i) {
    const double a = i * step, x = r * std::cos(a), y = r * std::sin(a), th = a + M_PI / 2;
    os << "FLASER 180";
    for (int k = 0; k < 180; ++k) {
      const double b = th - M_PI / 2 + k * M_PI / 180, c = std::cos(b), s = std::sin(b);
      const double d =
          std::min(rayBox(x, y, c, s, -5, -5, 5, 5), rayBox(x, y, c, s, 0.5, -0.5, 1.5, 0.5));
      os << ' ' << d;
    }
    os << ' ' << x << ' ' << y << ' ' << th << ' ' << x << ' ' << y << ' ' << th << ' ' << 10.0 + i
       << " host " << 10.0 + i << '\n';
    for (double u : {0.0, 0.5}) {
      const Pose2 o = wheelOdometry(i + u);
      os << "ODOM " << o.x << ' ' << o.y << ' ' << o.theta << " 0 0 0 " << 10.0 + i + u << " host "
         << 10.0 + i + u << '\n';
    }
  }
  return os.str();
}

// The room's lap is 18.85 m: a revisit gap of 8 m makes the second and
// third laps revisits.
CarmenTrialsOptions smallOptions() {
  CarmenTrialsOptions o;
  o.revisit_gap = 8;
  o.trial_poses = 5;
  return o;
}

TEST(CarmenTrials, MapsTheFirstVisitsAndCutsTrialsFromTheRevisitsTrainingFirst) {
  const carmen::CarmenLog log = carmen::parseCarmenLog(circlingLog(2.5), "room.log");
  const CarmenTrialsOptions o = smallOptions();
  const CarmenTrials t = carmenTrials(log, o);
  // A pose every 0.51 m (index i at t = 10 + i s): the poses within 2 m of
  // one 8 m or more before are those from 16.8 m of path on (the chord of
  // 2 m closes the lap), the first 33 of 92 are first visits.
  EXPECT_EQ(t.cut.kept_poses, 92u);
  EXPECT_EQ(t.cut.first_visit_poses, 33u);
  EXPECT_EQ(t.cut.revisiting_poses, 59u);
  // A node per metre of the first visits but those within 4 m of a revisit
  // less than 8 m of path later (the lap's last 4.2 m).
  EXPECT_EQ(t.map.poses.size() + t.cut.dropped_nodes, 17u);
  EXPECT_GE(t.cut.dropped_nodes, 3u);
  ASSERT_EQ(t.node_times.size(), t.map.poses.size());
  ASSERT_GE(t.train.size(), 4u);
  ASSERT_GE(t.test.size(), 4u);
  // Each trial starts at the previous one's last pose in its run (4 steps a
  // trial, so a run of R poses gives (R - 1) / 4).
  std::size_t shared = 0;
  for (const auto* set : {&t.train, &t.test})
    for (std::size_t k = 1; k < set->size(); ++k)
      if ((*set)[k].truth.front().t() == (*set)[k - 1].truth.back().t()) {
        EXPECT_EQ((*set)[k].scans.front(), (*set)[k - 1].scans.back());
        ++shared;
      }
  EXPECT_GE(shared, t.train.size() + t.test.size() - 4);
  EXPECT_LE(t.times.train_until, t.times.test_from);
  for (const auto* set : {&t.train, &t.test})
    for (const Trial& trial : *set) {
      ASSERT_EQ(trial.truth.size(), 5u);
      ASSERT_EQ(trial.odometry.size(), 4u);
      ASSERT_EQ(trial.scans.size(), 5u);
      for (const Scan& s : trial.scans)
        for (const Point2& p : s) EXPECT_LE(p.norm(), o.max_range + 1e-9);
    }
  // The map is never a trial's own pass: a node within 4 m of a trial pose
  // was recorded 8 m of path (16 poses) or more before or after it.
  ASSERT_EQ(t.times.train_spans.size(), t.train.size());
  ASSERT_EQ(t.times.test_spans.size(), t.test.size());
  std::size_t near = 0;
  for (const auto& [set, spans] :
       {std::pair{&t.train, &t.times.train_spans}, {&t.test, &t.times.test_spans}})
    for (std::size_t k = 0; k < set->size(); ++k) {
      EXPECT_EQ((*spans)[k].second - (*spans)[k].first, 4.0);
      for (std::size_t i = 0; i < 5; ++i)
        for (std::size_t j = 0; j < t.map.poses.size(); ++j) {
          if ((t.map.poses[j].t() - (*set)[k].truth[i].t()).norm() > 4) continue;
          ++near;
          EXPECT_GE(std::abs(t.node_times[j] - ((*spans)[k].first + i)) * 0.51, 8.0);
        }
    }
  EXPECT_GT(near, 0u);
  // The odometry is the log's: the wheel odometry's steps between the scans'
  // times (5% too long), not the reference's motion.
  const Pose2 d = t.test[0].truth[0].between(t.test[0].truth[1]);
  EXPECT_NEAR(t.test[0].odometry[0].t().norm(), 1.05 * d.t().norm(), 1e-4);
  EXPECT_NEAR(t.test[0].odometry[0].theta, d.theta, 1e-4);
  // Its noise is estimated on the first visits: a 5% scale error of 0.51 m
  // steps is about 2.6 cm per step, sigma_xy^2 = (0.05 d)^2 / 2 / (d / 10 m).
  EXPECT_NEAR(t.noise.sigma_xy, std::sqrt(0.0025 * 0.5355 * 10 / 2), 0.01);
  EXPECT_LT(t.noise.sigma_theta, 1e-3);
  EXPECT_GT(t.noise.odometry_steps, 10u);
}

TEST(CarmenTrials, SyntheticOdometryIsTheReferenceMotionWithDrawnNoise) {
  const carmen::CarmenLog log = carmen::parseCarmenLog(circlingLog(2.5), "room.log");
  CarmenTrialsOptions o = smallOptions();
  o.odometry = LogOdometry::kSynthetic;
  const CarmenTrials t = carmenTrials(log, o);
  const Pose2 d = t.test[0].truth[0].between(t.test[0].truth[1]);
  EXPECT_GT((t.test[0].odometry[0].t() - d.t()).norm(), 1e-6);
  EXPECT_LT((t.test[0].odometry[0].t() - d.t()).norm(), 0.2);
  EXPECT_EQ(t.noise.sigma_xy, o.sigma_xy);  // weighed with the noise drawn
  EXPECT_EQ(t.noise.odometry_steps, 0u);
  EXPECT_EQ(parseLogOdometry("synthetic"), LogOdometry::kSynthetic);
  EXPECT_EQ(parseLogOdometry("log"), LogOdometry::kLog);
  EXPECT_THROW(parseLogOdometry("wheels"), Error);
}

TEST(CarmenTrials, OdometryIsInterpolatedAtScanTimesAndItsNoiseEstimated) {
  const carmen::CarmenLog log = carmen::parseCarmenLog(
      "FLASER 3 1 1 1 0 0 0 0 0 0 0.5 h 0.5\n"
      "ODOM 0 0 3.1 0 0 0 0 h 0\n"
      "ODOM 2 0 -3.1 0 0 0 2 h 2\n",
      "odom.log");
  const OdometryTrack track(log);
  const Pose2 mid = track.at(1.0);
  EXPECT_NEAR(mid.x, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(mid.theta), M_PI, 1e-9);  // along the shorter arc through pi
  EXPECT_NEAR(track.at(2.5).x, 2.0, 1e-12);      // within the slack: the nearest
  try {
    track.at(3.5);
    ADD_FAILURE() << "a time past the ODOM records was answered";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("odom.log: no ODOM record within"), std::string::npos)
        << e.what();
  }
  const carmen::CarmenLog none =
      carmen::parseCarmenLog("FLASER 3 1 1 1 0 0 0 0 0 0 0.5 h 0.5\n", "none.log");
  EXPECT_THROW(OdometryTrack{none}, Error);
  // Steps of 1 m whose odometry says 1.1 m and 0.01 rad.
  double sxy = 0, sth = 0;
  estimateOdometryNoise(std::vector<Pose2>(4, Pose2(1, 0, 0)),
                        std::vector<Pose2>(4, Pose2(1.1, 0, 0.01)), 10.0, 0.05, &sxy, &sth);
  EXPECT_NEAR(sxy, std::sqrt(0.01 / 2 / 0.11), 1e-12);
  EXPECT_NEAR(sth, std::sqrt(1e-4 / 0.11), 1e-12);
}

TEST(CarmenTrials, RealScansMatchTheMapNodesScans) {
  const carmen::CarmenLog log = carmen::parseCarmenLog(circlingLog(2.5), "room.log");
  const CarmenTrials t = carmenTrials(log, smallOptions());
  Registry registry;
  registerBuiltins(registry);
  Localizer localizer(t.map, t.test, LocalizerConfig(), registry);
  const Localization l = localizer.localize(0, std::vector<char>(t.map.poses.size(), 1));
  EXPECT_EQ(l.l2g_factors, 4);  // every pose but the known start
  EXPECT_LT(localizer.rmse(std::vector<char>(t.map.poses.size(), 1)), 0.05);
}

// The gate refuses a match that disagrees with dead reckoning: at a tiny
// threshold every match of a trial, at none none; its covariance grows with
// the distance driven, in the cross direction through the heading's.
TEST(CarmenTrials, TheGateRefusesMatchesFarFromThePrediction) {
  const carmen::CarmenLog log = carmen::parseCarmenLog(circlingLog(2.5), "room.log");
  const CarmenTrials t = carmenTrials(log, smallOptions());
  Registry registry;
  registerBuiltins(registry);
  LocalizerConfig config;
  config.gate_chi2 = 1e-12;
  Localizer gated(t.map, t.test, config, registry);
  const Localization l = gated.localize(0, std::vector<char>(t.map.poses.size(), 1));
  EXPECT_EQ(l.l2g_factors, 0);
  EXPECT_EQ(l.gated, 4);
  for (const ScanMatch& m : l.matches) EXPECT_FALSE(m.ok);
  config.gate_chi2 = 1e6;
  Localizer open(t.map, t.test, config, registry);
  EXPECT_EQ(open.localize(0, std::vector<char>(t.map.poses.size(), 1)).l2g_factors, 4);

  Trial straight;
  straight.truth.assign(3, Pose2());
  straight.odometry.assign(2, Pose2(1, 0, 0));
  LocalizerConfig c;  // 30 cm and 0.1 degree per 10 m
  const std::vector<Eigen::Matrix3d> cov = deadReckoningCovariance(straight, c);
  const double vxy = 0.09 / 10, vth = std::pow(0.1 * M_PI / 180, 2) / 10;
  EXPECT_NEAR(cov[2](0, 0), 2 * vxy + 1e-6, 1e-12);
  EXPECT_NEAR(cov[2](2, 2), 2 * vth + 1e-6, 1e-12);
  // Across, the first step's heading error moves the second step sideways.
  EXPECT_NEAR(cov[2](1, 1), 2 * vxy + vth + 5e-6, 1e-12);
  EXPECT_NEAR(gateChi2(Pose2(0.3, 0, 0), Pose2(), Eigen::Matrix3d::Identity() * 0.01), 9, 1e-9);
}

TEST(CarmenTrials, RefusesLogsThatDoNotRevisitAndBadOptions) {
  // Less than a lap never comes back to its first visits.
  const carmen::CarmenLog half = carmen::parseCarmenLog(circlingLog(0.9), "half.log");
  CarmenTrialsOptions o = smallOptions();
  o.revisit_radius = 0.2;
  try {
    carmenTrials(half, o);
    FAIL() << "no trial revisits the map";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("half.log: 0 stretches"), std::string::npos) << e.what();
  }
  o = smallOptions();
  o.scans.tag = "RLASER";
  EXPECT_THROW(
      {
        try {
          carmenTrials(half, o);
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "half.log: no RLASER scans");
          throw;
        }
      },
      Error);
  for (auto [field, value, name] :
       {std::tuple<double CarmenTrialsOptions::*, double, const char*>{
            &CarmenTrialsOptions::revisit_gap, 0.0, "--revisit_gap"},
        {&CarmenTrialsOptions::max_range, 0.0, "--max_range"},
        {&CarmenTrialsOptions::revisit_radius, NAN, "--revisit_radius"},
        {&CarmenTrialsOptions::train_fraction, 0.0, "--train_fraction"}}) {
    CarmenTrialsOptions bad = smallOptions();
    bad.*field = value;
    try {
      bad.validate();
      ADD_FAILURE() << name << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(CarmenTrials, ExperimentRunsOnALogAndResumes) {
  const std::string dir = ::testing::TempDir() + "/moss_log_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/room.log";
  std::ofstream(path) << circlingLog(2.5);
  Registry registry;
  registerBuiltins(registry);
  ExperimentConfig c;
  c.source.data = path;
  c.source.log = smallOptions();
  c.sizes = {2, 4};
  c.climbs = 2;
  c.steps = 5;
  c.run.threads = 1;
  c.run.out = dir + "/out";
  std::ostringstream log;
  runExperiment(c, registry, log);
  std::ifstream rows(c.run.out + "/rows.csv");
  int n = 0;
  for (std::string line; std::getline(rows, line);) {
    if (n++ > 0) {
      EXPECT_EQ(line.rfind("room,", 0), 0u) << line;
    } else {  // both errors reported, whichever MOSS minimised
      EXPECT_NE(line.find("test_rmse,test_rmse_se,"), std::string::npos) << line;
      EXPECT_NE(line.find("test_mean_error,test_mean_error_se"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(n, 1 + 2 + 3 * 2);  // header, full map, no map, 3 methods x 2 C
  EXPECT_TRUE(std::filesystem::exists(c.run.out + "/points.csv"));
  // The full map's matches on the test trials, graded against the reference.
  EXPECT_GT(std::filesystem::file_size(c.run.out + "/matches_full_test.csv"), 100u);
  ExperimentConfig other = c;
  other.sizes = {500};  // more nodes than the map has: refused, nothing written
  other.run.out = dir + "/too_many";
  EXPECT_THROW(runExperiment(other, registry, log), Error);
  EXPECT_FALSE(std::filesystem::exists(other.run.out));
  other = c;
  other.run.climb = 0;  // one climb on a cluster: simulated worlds only, said so
  try {
    runExperiment(other, registry, log);
    ADD_FAILURE() << "--climb ran on a log";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "experiment: --climb is not available with --data");
  }
  other = c;
  other.source.log.revisit_gap = 9;  // another cut: refused, not mixed in
  EXPECT_THROW(runExperiment(other, registry, log), Error);
  other = c;
  other.localizer.objective = Objective::kSumOfNorms;  // another objective: the same
  EXPECT_THROW(runExperiment(other, registry, log), Error);
  other = c;
  other.source.read.no_return_range = 5;  // the log read otherwise: the same
  EXPECT_THROW(runExperiment(other, registry, log), Error);
  other.source.read = {};  // read as before: resumes, nothing left to run
  EXPECT_NO_THROW(runExperiment(other, registry, log));
  // The information calibrated on the training trials, and recorded.
  other = c;
  other.matches.calibrate_information = true;
  other.localizer.gate_chi2 = 11.34;
  other.run.out = dir + "/calibrated";
  std::ostringstream calibrated;
  runExperiment(other, registry, calibrated);
  EXPECT_NE(calibrated.str().find("information calibrated on the training trials (full map: "),
            std::string::npos)
      << calibrated.str();
  std::ifstream config(other.run.out + "/config.txt");
  const std::string text((std::istreambuf_iterator<char>(config)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("l2g_gate 11.34\ncalibrate_information 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("odometry log\n"), std::string::npos) << text;
  std::filesystem::remove_all(dir);
}

// hamal_moss experiment --data reads the log with the reader's flags
// (apps/carmen/carmen_log_flags.h) and refuses a gzip log cut short.
TEST(CarmenTrials, HamalMossTakesTheReaderFlags) {
  const std::string dir = ::testing::TempDir() + "/moss_reader_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string log = dir + "/back.log";  // FLASER steps 0.8 s back on line 2
  std::ofstream(log) << "FLASER 3 1 2 50 0 0 0 0 0 0 10 host 10\n"
                     << "FLASER 3 1 2 50 0.1 0 0 0.1 0 0 9.2 host 9.2\n";
  const std::string exe = testing::buildPath("apps/hamal_moss") +
                          " experiment --sizes 1 --output " + dir + "/out --data ";
  const auto strict = testing::runCommand(exe + log + " --max_time_reversal 0.5");
  EXPECT_EQ(strict.status, 1);
  EXPECT_NE(strict.output.find(log + ":2: time goes backwards: FLASER at 9.2 s after 10 s on line "
                                     "1 (0.8 s back; tolerance 0.5 s, max_time_reversal)"),
            std::string::npos)
      << strict.output;
  const auto bad = testing::runCommand(exe + log + " --no_return_range=-1");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.output.find("--no_return_range -1: must be a number of metres >= 0"),
            std::string::npos)
      << bad.output;
  std::ofstream(dir + "/room.log") << circlingLog(2.5);
  ASSERT_EQ(testing::runCommand("cd " + dir + " && gzip -k room.log && head -c $(( $(stat -c %s " +
                                "room.log.gz) / 2 )) room.log.gz > " + log + ".gz")
                .status,
            0);
  const auto cut = testing::runCommand(exe + log + ".gz --declared_max_range=false");
  EXPECT_EQ(cut.status, 1);
  EXPECT_NE(cut.output.find(log + ".gz: the gzip stream is cut short"), std::string::npos)
      << cut.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hamal::moss
