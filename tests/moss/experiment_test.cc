// The MOSS experiment (thesis sec. 5.5) as a resumable product: a finished
// run writes one row per (method, C) plus the full map and no map, a restart adds
// nothing (with or without swap reuse), a restart with other parameters
// (K, the L2G information) is refused, bad sizes fail early.
#include "apps/moss/experiment.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "backends/builtins.h"
#include "core/error.h"

namespace hamal::moss {
namespace {

int countLines(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// The refusal of a folder made with other parameters, naming the first one.
std::string otherParameters(const std::string& reason) {
  return "this directory holds a run with other parameters (" + reason + "); use another --output";
}

// The message runExperiment throws, "" when it runs.
std::string errorOf(const ExperimentConfig& c, const Registry& registry) {
  std::ostringstream log;
  try {
    runExperiment(c, registry, log);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Experiment, WritesEveryRowOnceAndResumes) {
  Registry registry;
  registerBuiltins(registry);
  const std::string out = ::testing::TempDir() + "/moss_experiment_" + std::to_string(getpid());
  std::filesystem::remove_all(out);
  ExperimentConfig c;
  c.source.world = "CORRIDOR";
  c.sizes = {1, 2};
  c.train = 2;
  c.test = 2;
  c.climbs = 2;
  c.steps = 3;
  c.run.out = out;
  std::ostringstream log;
  runExperiment(c, registry, log);
  const std::string rows = out + "/rows.csv";
  // header, full map, no map, 3 methods x 2 C
  EXPECT_EQ(countLines(rows), 1 + 2 + 3 * 2);
  EXPECT_TRUE(std::filesystem::exists(out + "/map.csv"));
  EXPECT_EQ(countLines(out + "/walls.csv"), 1 + 8);
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 9);
  c.sizes = {1, 2, 3};
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 12);  // only C = 3 added
  c.reuse = false;                  // the same selections, so the folder resumes
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 12);
  c.matches.matcher.information = ScanMatcherConfig::Information::kCensi;  // other factors: refused
  EXPECT_EQ(
      errorOf(c, registry),
      out + "/config.txt: " + otherParameters("information is not set there and 'censi' now"));
  c.matches.matcher.information = ScanMatcherConfig::Information::kHessian;
  c.steps = 4;
  EXPECT_EQ(errorOf(c, registry),
            out + "/config.txt: " + otherParameters("steps is '3' there and '4' now"));
  std::filesystem::remove_all(out);
}

// The rows of a folder without the columns that time or count work.
std::vector<std::string> selections(const std::string& out) {
  std::ifstream in(out + "/rows.csv");
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string field; std::getline(ss, field, ',');) f.push_back(field);
    rows.push_back(f.at(1) + "," + f.at(2) + "," + f.at(4) + "," + f.at(5) + "," + f.at(12));
  }
  return rows;
}

// The T climbs run one per process (a cluster's array tasks, --climb t) and
// then picked by an ordinary run give a local run's selections; a climb run
// writes no rows, and a climb index past T is an error naming it.
TEST(Experiment, ClimbsRunApartThenPickedMatchOneRun) {
  Registry registry;
  registerBuiltins(registry);
  const std::string base = ::testing::TempDir() + "/moss_climbs_" + std::to_string(getpid());
  std::filesystem::remove_all(base);
  ExperimentConfig c;
  c.source.world = "CORRIDOR";
  c.sizes = {3};
  c.train = 2;
  c.test = 2;
  c.climbs = 2;
  c.steps = 4;
  c.run.threads = 1;
  c.run.out = base + "/whole";
  std::ostringstream log;
  runExperiment(c, registry, log);
  c.run.out = base + "/apart";
  c.run.verify_only = true;
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(c.run.out + "/rows.csv"), 1);  // the header alone
  c.run.verify_only = false;
  for (int t = 0; t < c.climbs; ++t) {
    c.run.climb = t;
    runExperiment(c, registry, log);
  }
  EXPECT_EQ(countLines(c.run.out + "/rows.csv"), 1);
  c.run.climb = 2;
  EXPECT_EQ(errorOf(c, registry), "experiment: --climb 2: the climbs are 0 to 1 (T = --climbs 2)");
  c.run.climb = -1;
  runExperiment(c, registry, log);
  EXPECT_EQ(selections(c.run.out), selections(base + "/whole"));
  EXPECT_EQ(countLines(c.run.out + "/rows.csv"), 1 + 2 + 3);  // header, full and no map, C = 1..3
  std::filesystem::remove_all(base);
}

// The full map's row of a finished experiment folder ("" if none).
std::string fullMapRow(const std::string& out) {
  std::ifstream in(out + "/rows.csv");
  for (std::string line; std::getline(in, line);)
    if (line.find(",full,") != std::string::npos) return line;
  return "";
}

// --censi_sigma reaches the L2G factors (another sigma_d, other estimates),
// and a Censi run's folder records it when it is not the laser's: another
// --censi_sigma is another run.
TEST(Experiment, ACensiRunUsesAndRecordsItsSigma) {
  Registry registry;
  registerBuiltins(registry);
  const std::string out = ::testing::TempDir() + "/moss_censi_" + std::to_string(getpid());
  std::filesystem::remove_all(out);
  std::filesystem::remove_all(out + "_laser");
  ExperimentConfig c;
  c.source.world = "CORRIDOR";
  c.sizes = {1};
  c.methods = {"equidistant"};
  c.train = 2;
  c.test = 2;
  c.climbs = 1;
  c.steps = 1;
  c.run.out = out + "_laser";
  c.matches.matcher.information = ScanMatcherConfig::Information::kCensi;
  std::ostringstream log;
  runExperiment(c, registry, log);  // sigma_d of the laser, 2 cm
  c.matches.censi_sigma = 0.05;
  c.run.out = out;
  runExperiment(c, registry, log);
  std::ifstream config(out + "/config.txt");
  std::stringstream text;
  text << config.rdbuf();
  EXPECT_NE(text.str().find("censi_sigma 0.05\n"), std::string::npos) << text.str();
  // world,method,C,M,train_rmse,test_rmse: the same trials, other errors.
  const auto errors = [](const std::string& row) {
    std::stringstream ss(row);
    std::string field, kept;
    for (int k = 0; k < 6 && std::getline(ss, field, ','); ++k) kept += field + ",";
    return kept;
  };
  const std::string laser = errors(fullMapRow(out + "_laser")), wider = errors(fullMapRow(out));
  ASSERT_FALSE(laser.empty());
  EXPECT_EQ(laser.rfind("corridor,full,21,21,", 0), 0u) << laser;
  EXPECT_NE(laser, wider);
  EXPECT_EQ(errorOf(c, registry), "");  // the same run resumes
  c.matches.censi_sigma = 0.0;
  EXPECT_EQ(errorOf(c, registry),
            out + "/config.txt: " + otherParameters("censi_sigma is '0.05' there and not set now"));
  c.matches.censi_sigma = 0.02;  // the laser's, said aloud: the 2 cm folder resumes
  c.run.out = out + "_laser";
  EXPECT_EQ(errorOf(c, registry), "");
  std::filesystem::remove_all(out);
  std::filesystem::remove_all(out + "_laser");
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
void writeAll(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// A folder is verified before a run extends it: a torn last row (a kill
// between a row's fields and its line break) is dropped and run again, never
// counted as done nor glued to the next row; a damaged row, a missing
// config.txt and other parameters are refused, naming the line or the
// parameter.
TEST(Experiment, AResumeVerifiesTheFolder) {
  Registry registry;
  registerBuiltins(registry);
  const std::string out = ::testing::TempDir() + "/moss_verify_" + std::to_string(getpid());
  std::filesystem::remove_all(out);
  ExperimentConfig c;
  c.source.world = "CORRIDOR";
  c.sizes = {1, 2};
  c.methods = {"equidistant"};
  c.train = 2;
  c.test = 2;
  c.climbs = 1;
  c.steps = 1;
  c.run.out = out;
  const std::string rows = out + "/rows.csv", config = out + "/config.txt";
  EXPECT_EQ(errorOf(c, registry), "");
  const std::string whole = readAll(rows);
  ASSERT_EQ(countLines(rows), 1 + 2 + 2);  // header, full and no map, 2 rows
  const std::size_t last_row = whole.rfind('\n', whole.size() - 2) + 1;
  // Cut mid-field, then mid-row: the row is run again and the file is whole.
  for (std::size_t cut : {last_row + 12, whole.size() - 3}) {
    writeAll(rows, whole.substr(0, cut));
    std::ostringstream log;
    runExperiment(c, registry, log);
    EXPECT_NE(log.str().find("dropped a torn last row"), std::string::npos) << log.str();
    EXPECT_EQ(readAll(rows).substr(0, last_row), whole.substr(0, last_row));
    EXPECT_EQ(countLines(rows), 5);
    const std::string redone = readAll(rows).substr(last_row);
    EXPECT_EQ(std::count(redone.begin(), redone.end(), ','), 18) << redone;
    EXPECT_EQ(redone.rfind("corridor,equidistant,2,21,", 0), 0u) << redone;
  }
  // A damaged row in the middle: refused with its line.
  std::string damaged = whole;
  damaged.replace(damaged.find(",equidistant,1,"), 15, ",equidistant,x4,");
  writeAll(rows, damaged);
  EXPECT_EQ(errorOf(c, registry), rows + ":4: C is 'x4', not a non-negative integer");
  damaged = whole;
  damaged.erase(damaged.find(",equidistant,1,"), 12);
  writeAll(rows, damaged);
  EXPECT_EQ(errorOf(c, registry),
            rows + ":4: 18 fields, the header has 19 (a damaged results file)");
  writeAll(rows, whole);
  // Other parameters, named; no config at all.
  c.seed = 2;
  EXPECT_EQ(errorOf(c, registry), config + ": " + otherParameters("seed is '1' there and '2' now"));
  c.seed = 1;
  std::filesystem::remove(config);
  EXPECT_EQ(errorOf(c, registry), rows + ": results without " + config +
                                      ", so nothing says which parameters made them; use "
                                      "another --output");
  EXPECT_EQ(readAll(rows), whole);
  std::filesystem::remove_all(out);
}

TEST(Experiment, BadParametersFailBeforeAnythingRuns) {
  Registry registry;
  registerBuiltins(registry);
  ExperimentConfig c;
  c.run.out = ::testing::TempDir() + "/moss_never_made";
  c.sizes = {22};
  EXPECT_EQ(errorOf(c, registry),
            "experiment: C = 22 nodes requested from a map of M = 21 nodes (C must be in [1, M])");
  c.sizes = {3};
  c.climbs = 0;
  EXPECT_EQ(errorOf(c, registry), "experiment: T (--climbs) must be at least 1");
  c.climbs = 1;
  c.steps = 0;
  EXPECT_EQ(errorOf(c, registry), "experiment: K (--steps) must be at least 1");
  c.steps = 1;
  c.train = 0;
  EXPECT_EQ(errorOf(c, registry), "experiment: --train and --test must be at least 1");
  c.train = 1;
  c.matches.censi_sigma = -0.02;
  EXPECT_EQ(errorOf(c, registry),
            "experiment: --censi_sigma must be a positive number of metres (0: the laser's)");
  c.matches.censi_sigma = 0;
  c.methods = {"random"};
  EXPECT_EQ(errorOf(c, registry), "experiment: unknown method 'random' (equidistant, ssm, moss)");
  c.methods = {"moss"};
  c.run.out = "";
  EXPECT_EQ(errorOf(c, registry), "experiment: --output is required");
  EXPECT_FALSE(std::filesystem::exists(::testing::TempDir() + "/moss_never_made"));
  EXPECT_EQ(parseSizes("1-3,6"), std::vector<int>({1, 2, 3, 6}));
  EXPECT_THROW(parseSizes("x"), Error);
  EXPECT_THROW(parseSizes("5-2"), Error);
}

}  // namespace
}  // namespace hamal::moss
