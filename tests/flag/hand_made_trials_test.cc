// Figs. 4.8 and 4.10's trials are recordings made by hand (point
// measurements, data_association_experiments.h), not scans: the detector
// option cannot change them, as apps/flag/README.md states.
#include <gtest/gtest.h>

#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

TEST(HandMadeTrials, TheDetectorDoesNotChangeFigs48And410) {
  const std::string flag = testing::buildPath("apps/hamal_flag");
  for (const char* experiment : {"dynamic", "static"}) {
    const std::string trials = flag + " trials " + experiment + " --trials 2";
    const testing::CommandResult scan = testing::runCommand(trials + " --detector scan");
    const testing::CommandResult oracle = testing::runCommand(trials + " --detector oracle");
    ASSERT_EQ(scan.status, 0) << scan.output;
    ASSERT_EQ(oracle.status, 0) << oracle.output;
    EXPECT_GT(scan.output.size(), 100u);
    EXPECT_EQ(scan.output, oracle.output) << experiment;
  }
}

}  // namespace
}  // namespace hamal
