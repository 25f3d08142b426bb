// hamal_flag and scripts/flag.sh's driver as a user runs them: a run prints
// its errors, a bad floor plan is refused naming file and line (exit 1), a
// trial batch writes its CSV, and the experiment driver resumes instead of
// redoing finished chunks.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

using testing::CommandResult;
CommandResult run(const std::string& command_line) { return testing::runCommand(command_line); }

std::string flagBinary() { return testing::buildPath("apps/hamal_flag"); }

class HamalFlag : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/hamal_flag_XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
  }
  void TearDown() override { run("rm -rf '" + dir_ + "'"); }
  std::string dir_;
};

TEST_F(HamalFlag, RunPrintsErrorsAndStepTimes) {
  const CommandResult r = run(flagBinary() + " run --world corridor --seed 2");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("FLAG            mean |error|"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dead reckoning"), std::string::npos);
  EXPECT_NE(r.output.find("p99"), std::string::npos);
}

// The updates line says how many steps were batches and which criterion
// called each, so a user sees where the step time's p99 comes from.
TEST_F(HamalFlag, RunSaysWhichUpdatesWereBatchesAndWhy) {
  CommandResult r = run(flagBinary() + " run --world corridor --seed 2");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::size_t at = r.output.find("  updates: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
  EXPECT_NE(line.find(" batch ("), std::string::npos) << line;
  EXPECT_NE(line.find("1 first update"), std::string::npos) << line;
  EXPECT_NE(line.find("incremental cost x n_lc >= batch cost"), std::string::npos) << line;
  EXPECT_NE(line.find(" incremental ("), std::string::npos) << line;
  EXPECT_NE(line.find("thread CPU p99 of the batch steps "), std::string::npos) << line;
  // The batch Cholesky back-end batches every step, and says why.
  r = run(flagBinary() + " run --world corridor --seed 2 --backend cholesky");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(" batch ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" sqrt-SAM: batch solve at every update), 0 incremental"),
            std::string::npos)
      << r.output;
}

// The command line and the library default to the same back-end spec:
// AprilSAM with n_lc=1 (flag_options.h says why).
TEST_F(HamalFlag, DefaultBackendIsAprilsamWithOneLoopClosureNode) {
  const CommandResult r = run(flagBinary() + " run --world corridor --seed 1");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("seed 1, back-end aprilsam:n_lc=1\n"), std::string::npos) << r.output;
}

TEST_F(HamalFlag, BadInputIsRefusedWithFileAndLine) {
  const std::string plan = dir_ + "/bad.plan";
  std::ofstream(plan) << "WALL 0 0 10 0\nCORNER 0 0 0\nPATH 1 0.5 zero\n";
  CommandResult r = run(flagBinary() + " run --world " + plan);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("hamal_flag: error: " + plan + ":3:"), std::string::npos) << r.output;
  r = run(flagBinary() + " run --world corridor --gate -1");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("gate must be > 0"), std::string::npos) << r.output;
  r = run(flagBinary() + " run --world corridor --range_sigma -0.1");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("range sigma must be > 0"), std::string::npos) << r.output;
  r = run(flagBinary() + " trials nonsense");
  EXPECT_EQ(r.status, 1);
}

// Bad input as a user meets it: a floor plan with no
// corners, a corner on no wall, a path leaving the world, a negative noise
// or gate, a malformed line. Each exits 1 with the file, the line where one
// record is at fault, and the reason; an option's message names the option.
TEST_F(HamalFlag, EachBadInputNamesFileLineAndReason) {
  const std::string walls =
      "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n";  // lines 1-4
  const struct {
    const char* name;
    std::string text, expected;
  } plans[] = {
      {"no_corners", walls + "PATH 1 1\nPATH 9 1\n", ": the floor plan has no corners"},
      {"corner_off_wall", walls + "CORNER 0 0 0\nCORNER 1 5 5\nPATH 1 1\nPATH 9 1\n",
       ":6: corner 1 at (5, 5) lies on no wall"},
      {"path_out", walls + "CORNER 0 0 0\nPATH 1 1\nPATH 9 1\nPATH 9 14\n",
       ":8: waypoint 2 at (9, 14) leaves the world"},
      {"path_through_wall", walls + "WALL 5 0 5 8\nCORNER 0 0 0\nPATH 1 1\nPATH 9 1\n",
       ":8: the path from waypoint 0 to 1 goes through the wall (5, 0)-(5, 8) of line 5"},
      {"malformed", walls + "CORNER 0 0 zero\n", ":5: "},
      {"negative_height", walls + "CORNER 0 0 0\nOBJECT 1 1 -2\n", ":6: height must be >= 0"},
      {"negative_speed", walls + "PERSON 1 1 2 2 0 -1\n", ":5: speed must be > 0"},
      // Landmark ids have 56 bits: 2^56 would alias corner 0.
      {"huge_id", walls + "CORNER 0 0 0\nCORNER 72057594037927936 10 0\n",
       ":6: id 72057594037927936 is larger than the largest landmark id 72057594037927935"},
      {"huge_hides_id", walls + "CORNER 0 0 0\nOBJECT 1 1 2 18446744073709551615\n",
       ":6: hides_id 18446744073709551615 is larger than the largest landmark id"},
  };
  for (const auto& p : plans) {
    const std::string file = dir_ + "/" + p.name + ".plan";
    std::ofstream(file) << p.text;
    const CommandResult r = run(flagBinary() + " run --world " + file);
    EXPECT_EQ(r.status, 1) << p.name << ": " << r.output;
    EXPECT_NE(r.output.find("hamal_flag: error: " + file + p.expected), std::string::npos)
        << p.name << ": " << r.output;
  }
  const struct {
    const char* flags;
    const char* expected;
  } options[] = {
      {"--gate -0.5", "gate must be > 0"},
      {"--gate nan", "gate must be > 0"},
      {"--consistency_threshold -0.1", "consistency threshold must be > 0"},
      {"--landmark_sigma -0.1", "landmark sigma must be > 0"},
      {"--label_sigma -0.1", "label sigma must be >= 0"},
      {"--range_sigma -0.05", "range sigma must be > 0"},
      {"--odom_sigma_x -0.1", "odometry sigma x must be > 0"},
      {"--bearing_sigma_deg -1", "bearing sigma must be > 0"},
      {"--world_range_sigma -0.05", "world range sigma must be >= 0"},
      {"--world_odom_sigma_y -0.1", "world odometry sigma y must be >= 0"},
      {"--scan_range_sigma -0.01", "scan range sigma must be >= 0"},
      {"--detector sonar", "--detector must be scan, oracle or oracle_in_view, not 'sonar'"},
      {"--fit_tolerance 0", "fit_tolerance must be > 0"},
      {"--min_segment_points 1", "min_segment_points must be >= 3"},
      {"--min_corner_angle_deg 150", "min_corner_angle < max_corner_angle"},
      // Infinite is no value, and zero is no weight: named, not an "inf" factor.
      {"--range_sigma inf", "range sigma must be > 0 and finite, got inf"},
      {"--label_sigma inf", "label sigma must be >= 0 and finite"},
      {"--gate inf", "gate must be > 0 and finite, got inf"},
      {"--range_sigma 0", "range sigma must be > 0 and finite, got 0"},
      {"--bearing_sigma_deg 0", "bearing sigma must be > 0 and finite, got 0"},
  };
  for (const auto& o : options) {
    const CommandResult r = run(flagBinary() + " run --world corridor " + o.flags);
    EXPECT_EQ(r.status, 1) << o.flags << ": " << r.output;
    EXPECT_NE(r.output.find(o.expected), std::string::npos) << o.flags << ": " << r.output;
  }
  CommandResult r = run(flagBinary() + " run --world ofice");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("ofice: neither a built-in world (office, corridor) nor a floor-plan "
                          "file that can be opened"),
            std::string::npos)
      << r.output;
  // The label noise is an option: a good file is not blamed for it.
  const std::string good = dir_ + "/path_out.plan";
  std::ofstream(good) << walls << "CORNER 0 0 0\nPATH 1 1\nPATH 9 1\n";
  r = run(flagBinary() + " run --world " + good + " --label_sigma -0.1");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("hamal_flag: error: label sigma must be >= 0"), std::string::npos)
      << r.output;
  r = run(flagBinary() + " run --world " + dir_);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find(dir_ + ": is a directory, not a file"), std::string::npos) << r.output;
}

TEST_F(HamalFlag, WorldRoundTripsThroughAFile) {
  const std::string plan = dir_ + "/office.plan";
  ASSERT_EQ(run(flagBinary() + " world office --output " + plan).status, 0);
  const CommandResult a = run(flagBinary() + " run --world " + plan);
  const CommandResult b = run(flagBinary() + " run --world office");
  ASSERT_EQ(a.status, 0) << a.output;
  // The same labels and the same simulation: the same errors.
  const auto errors = [](const std::string& s) { return s.substr(s.find("FLAG  "), 120); };
  EXPECT_EQ(errors(a.output), errors(b.output));
}

TEST_F(HamalFlag, ExperimentDriverWritesRowsAndResumes) {
  const std::string py = "/usr/bin/python3";
  if (access(py.c_str(), X_OK) != 0) GTEST_SKIP() << "no " << py;
  const std::string cmd = "HAMAL_FLAG=" + flagBinary() + " " + py + " " +
                          std::string(HAMAL_SOURCE_DIR) +
                          "/apps/flag/flag_experiments.py dynamic --trials 6 --chunk 3 "
                          "--jobs 2 --results " +
                          dir_;
  CommandResult r = run(cmd);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("[2/2] chunks"), std::string::npos) << r.output;
  std::ifstream rows(dir_ + "/dynamic/trials.csv");
  std::string line;
  int n = 0;
  while (std::getline(rows, line)) ++n;
  EXPECT_EQ(n, 1 + 6 * 2);  // header, 6 trials x 2 arms
  r = run(cmd);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("2 of 2 chunks already done"), std::string::npos) << r.output;
}

// The real-log experiment: a row per arm and seed with the split's start,
// the table with the targets' verdict and the detector's precision and
// recall, and the synthetic-odometry arm.
TEST_F(HamalFlag, CarmenExperimentWritesRowsAndTheTargetsVerdict) {
  HAMAL_REQUIRE_DATA(aces, "carmen/aces.log");
  const std::string py = "/usr/bin/python3";
  if (access(py.c_str(), X_OK) != 0) GTEST_SKIP() << "no " << py;
  const std::string data_dir = aces.substr(0, aces.rfind("/carmen/"));
  const std::string cmd = "HAMAL_FLAG=" + flagBinary() + " " + py + " " +
                          std::string(HAMAL_SOURCE_DIR) +
                          "/apps/flag/flag_experiments.py carmen --logs aces --trials 1 "
                          "--jobs 2 --data-dir " +
                          data_dir + " --results " + dir_;
  CommandResult r = run(cmd);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("| aces | 1 |"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Targets (issue 46)"), std::string::npos) << r.output;
  std::ifstream rows(dir_ + "/carmen/trials.csv");
  std::string line, header;
  std::getline(rows, header);
  EXPECT_NE(header.find("start_scan"), std::string::npos) << header;
  EXPECT_NE(header.find("detector_precision,detector_recall"), std::string::npos) << header;
  EXPECT_NE(header.find("detector_precision_log,detector_recall_log"), std::string::npos) << header;
  EXPECT_NE(r.output.find("detector precision | detector recall |"), std::string::npos) << r.output;
  int n = 0, synthetic = 0;
  while (std::getline(rows, line)) {
    ++n;
    synthetic += line.find(",synthetic,") != std::string::npos;
  }
  EXPECT_EQ(n, 3);  // dead reckoning, known association, FLAG
  EXPECT_EQ(synthetic, 0);
  r = run(flagBinary() + " carmen --data " + aces + " --odometry synthetic --output " + dir_ +
          "/s.csv");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream s(dir_ + "/s.csv");
  std::getline(s, header);
  std::getline(s, line);
  EXPECT_NE(line.find(",synthetic,"), std::string::npos) << line;
  // The detector's precision and recall on every run (detector_evaluation.h).
  r = run(flagBinary() + " carmen --data " + aces);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("held-out key scans against the map's corners in view"),
            std::string::npos)
      << r.output;
  r = run(flagBinary() + " carmen --data " + aces + " --odometry raw");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("--odometry must be log or synthetic"), std::string::npos) << r.output;
}

// carmen --trajectory: per arm the poses the ATE grades, so their RMSE
// against the reference is the ATE of the rows.
TEST_F(HamalFlag, CarmenTrajectoryIsWhatTheAteGrades) {
  HAMAL_REQUIRE_DATA(aces, "carmen/aces.log");
  const CommandResult r =
      run(flagBinary() + " carmen --data " + aces + " --consistency_sigmas 3 --output " + dir_ +
          "/rows.csv --trajectory " + dir_ + "/poses.csv");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto fields = [](const std::string& line) {
    std::vector<std::string> f;
    std::stringstream in(line);
    for (std::string x; std::getline(in, x, ',');) f.push_back(x);
    return f;
  };
  std::ifstream rows(dir_ + "/rows.csv");
  std::string line;
  std::getline(rows, line);
  const std::vector<std::string> header = fields(line);
  const auto column = [&](const char* name) {
    return std::size_t(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::map<std::string, double> ate;
  std::size_t poses = 0;
  while (std::getline(rows, line)) {
    const std::vector<std::string> f = fields(line);
    ate[f.at(column("arm"))] = std::stod(f.at(column("ate_m")));
    poses = std::stoul(f.at(column("poses")));
  }
  ASSERT_EQ(ate.size(), 3u);
  std::ifstream trajectory(dir_ + "/poses.csv");
  std::getline(trajectory, line);
  EXPECT_EQ(line, "seed,arm,pose,truth_x,truth_y,truth_theta,x,y,theta,factors");
  std::map<std::string, double> squares;
  std::map<std::string, std::size_t> count;
  std::size_t factors = 0;
  while (std::getline(trajectory, line)) {
    const std::vector<std::string> f = fields(line);
    ASSERT_EQ(f.size(), 10u) << line;
    const double dx = std::stod(f[6]) - std::stod(f[3]), dy = std::stod(f[7]) - std::stod(f[4]);
    squares[f[1]] += dx * dx + dy * dy;
    ++count[f[1]];
    if (f[1] == "FLAG") factors = std::stoul(f[9]);
  }
  EXPECT_GT(factors, 0u);
  for (const auto& [arm, value] : ate) {
    ASSERT_EQ(count[arm], poses) << arm;
    EXPECT_NEAR(std::sqrt(squares[arm] / double(poses)), value, 1e-5 * value + 1e-9) << arm;
  }
}

}  // namespace
}  // namespace hamal
