// moss_report.py states the thesis' claims as the rows say, not as the
// thesis does: on a SQUARE folder whose MOSS is best at C = 11, the claim
// that C = 21 is best (sec. 5.5.2) does not hold, and the best C's map is
// judged against the full map, both at the C the test error picks and at
// the one the training error picks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "testing/command.h"

namespace hamal::moss {
namespace {

TEST(MossReport, JudgesTheBestCAndTheThesisC21Claim) {
  const std::string py = "/usr/bin/python3";
  if (access(py.c_str(), X_OK) != 0) GTEST_SKIP() << "no " << py;
  const std::string dir = ::testing::TempDir() + "/moss_report_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/rows.csv")
      << "world,method,C,M,train_rmse,test_rmse,test_rmse_se,seconds,evaluations,"
         "ms_per_evaluation,cache_hits,cache_misses,nodes,trials_localized_fraction,"
         "train_mean_error,test_mean_error,test_mean_error_se\n"
         "SQUARE,full,204,204,0.1,0.137,0.01,0,0,0,0,0,,0,0.1,0.080,0.01\n"
         "SQUARE,moss,11,204,0.07,0.095,0.01,1,1,1,0,0,1 2,0,0.05,0.085,0.01\n"
         "SQUARE,moss,21,204,0.06,0.417,0.09,1,1,1,0,0,1 2,0,0.05,0.200,0.02\n";
  std::ofstream(dir + "/walls.csv") << "x1,y1,x2,y2\n";
  std::ofstream(dir + "/map.csv") << "node,x,y,theta\n0,0,0,0\n1,1,0,0\n2,2,0,0\n";
  const testing::CommandResult r = testing::runCommand(py + " " + std::string(HAMAL_SOURCE_DIR) +
                                                       "/apps/moss/moss_report.py " + dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("best overall performance (sec. 5.5.2): does not hold (MOSS's lowest "
                          "test RMSE at C = 11)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("best C (C = 11, test RMSE 0.095 +- 0.030 m) at least as good as the "
                          "full map (0.137 m): holds"),
            std::string::npos)
      << r.output;
  // In eq. 5.3's mean norm the full map is better than MOSS at every C.
  EXPECT_NE(r.output.find("in eq. 5.3's mean error norm (C = 11, 0.085 +- 0.030 m; full map "
                          "0.080 m): does not hold"),
            std::string::npos)
      << r.output;
  // The training error picks C = 21, whose test error is above the full map's.
  EXPECT_NE(r.output.find("at the C its training error picks (C = 21, test RMSE 0.417 +- 0.270 "
                          "m): does not hold"),
            std::string::npos)
      << r.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hamal::moss
