// hamal_pcm as a user runs it: on a world hamal_spoil spoiled, batch and
// incremental PCM grade against the false-edge list, the exact result says
// so, each mode prints the threshold it tested with, and a bad option is an
// error naming it (exit 1).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include "apps/generator/manhattan_world.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "core/graph_io.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

std::string app(const std::string& name) { return testing::buildPath("apps/" + name); }

// The number printed after `label`, NaN when there is none.
double thresholdAfter(const std::string& output, const std::string& label) {
  const std::size_t at = output.find(label);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(output.c_str() + at + label.size(), nullptr);
}

TEST(HamalPcm, GradesASpoiledWorldAndRefusesBadOptions) {
  const std::string dir = ::testing::TempDir() + "/hamal_pcm_" + std::to_string(getpid());
  ASSERT_EQ(testing::runCommand("mkdir -p " + dir).status, 0);
  apps::ManhattanWorldOptions w;
  w.poses = 400;
  w.seed = 3;
  const auto world = apps::generateManhattanWorld(w);
  writeG2o(dir + "/clean.g2o", world.graph.initial, world.graph.factors);
  auto r = testing::runCommand(app("hamal_spoil") + " --data " + dir +
                               "/clean.g2o --outliers 40 --seed 5 --output " + dir + "/s.g2o");
  ASSERT_EQ(r.status, 0) << r.output;
  r = testing::runCommand(app("hamal_pcm") + " --data " + dir + "/s.g2o");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("exact (a maximum clique)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("false accepted 0 of 40"), std::string::npos) << r.output;
  const double batch = thresholdAfter(r.output, "batch: threshold ");
  r = testing::runCommand(app("hamal_pcm") + " --data " + dir + "/s.g2o --incremental");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("at most"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("false accepted 0 of 40"), std::string::npos) << r.output;
  // Each mode prints the threshold it tested with: batch tests a closure
  // against every other, so its threshold is the looser.
  const double incremental = thresholdAfter(r.output, "incremental: threshold ");
  EXPECT_NEAR(incremental, robust::defaultPcmOptions().threshold, 1e-3) << r.output;
  EXPECT_GT(batch, incremental + 1) << r.output;
  r = testing::runCommand(app("hamal_pcm") + " --data " + dir + "/s.g2o --options pcm_threshold=0");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("pcm_threshold"), std::string::npos) << r.output;
  testing::runCommand("rm -rf " + dir);
}

}  // namespace
}  // namespace hamal
