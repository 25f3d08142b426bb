// The MOSS experiment (thesis sec. 5.5) as a resumable product: a finished
// run writes one row per (method, C) plus the full map, a restart adds
// nothing (with or without swap reuse), a restart with other parameters
// (K, the L2G information) is refused, bad sizes fail early.
#include "apps/moss/experiment.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

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

TEST(Experiment, WritesEveryRowOnceAndResumes) {
  Registry registry;
  registerBuiltins(registry);
  const std::string out = ::testing::TempDir() + "/moss_experiment_" + std::to_string(getpid());
  std::filesystem::remove_all(out);
  ExperimentConfig c;
  c.world = "CORRIDOR";
  c.sizes = {1, 2};
  c.train = 2;
  c.test = 2;
  c.climbs = 2;
  c.steps = 3;
  c.out = out;
  std::ostringstream log;
  runExperiment(c, registry, log);
  const std::string rows = out + "/rows.csv";
  EXPECT_EQ(countLines(rows), 1 + 1 + 3 * 2);  // header, full map, 3 methods x 2 C
  EXPECT_TRUE(std::filesystem::exists(out + "/map.csv"));
  EXPECT_EQ(countLines(out + "/walls.csv"), 1 + 8);
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 8);
  c.sizes = {1, 2, 3};
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 11);  // only C = 3 added
  c.reuse = false;                  // the same selections, so the folder resumes
  runExperiment(c, registry, log);
  EXPECT_EQ(countLines(rows), 11);
  c.matcher.information = ScanMatcherConfig::Information::kCensi;  // other factors: refused
  EXPECT_THROW(runExperiment(c, registry, log), Error);
  c.matcher.information = ScanMatcherConfig::Information::kHessian;
  c.steps = 4;
  EXPECT_THROW(runExperiment(c, registry, log), Error);
  std::filesystem::remove_all(out);
}

TEST(Experiment, BadParametersFailBeforeAnythingRuns) {
  Registry registry;
  registerBuiltins(registry);
  ExperimentConfig c;
  c.out = ::testing::TempDir() + "/moss_never_made";
  c.sizes = {22};
  EXPECT_THROW(runExperiment(c, registry, std::cerr), Error);
  c.sizes = {3};
  c.climbs = 0;
  EXPECT_THROW(runExperiment(c, registry, std::cerr), Error);
  c.climbs = 1;
  c.steps = 0;
  EXPECT_THROW(runExperiment(c, registry, std::cerr), Error);
  c.steps = 1;
  c.methods = {"random"};
  EXPECT_THROW(runExperiment(c, registry, std::cerr), Error);
  EXPECT_FALSE(std::filesystem::exists(c.out));
  EXPECT_EQ(parseSizes("1-3,6"), std::vector<int>({1, 2, 3, 6}));
  EXPECT_THROW(parseSizes("x"), Error);
  EXPECT_THROW(parseSizes("5-2"), Error);
}

}  // namespace
}  // namespace hamal::moss
