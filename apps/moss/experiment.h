// Experiment: the map-size sweeps of thesis sec. 5.5 (figs. 5.6/5.7 on
// CORRIDOR, 5.9/5.10 on SQUARE) as one resumable run.
//
// One mapping run gives the prior map (or a real log's first traversal,
// carmen_trials.h); S training and S' test trials are
// drawn from separate random streams. For each C and method (Equidistant,
// SSM, MOSS) the method selects C nodes (MOSS from the training trials) and
// the selection is scored on the test trials; the full map (C = M) is the
// reference line. Rows are appended to <out>/rows.csv as they finish and a
// restarted run skips the rows already there (MOSS climbs also resume from
// their checkpoints in <out>/climbs/); <out>/map.csv and <out>/walls.csv
// hold what the plots draw. <out>/config.txt records the parameters, and a
// restart with other parameters is refused rather than mixed in. The T climbs
// of each C may also run as separate processes (`climb`, e.g. Slurm array
// tasks: apps/moss/moss_experiment.py), the best picked by a run after them.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "apps/moss/carmen_trials.h"
#include "apps/moss/localizer.h"
#include "apps/moss/moss_selection.h"
#include "apps/moss/trials.h"
#include "apps/moss/world.h"

namespace hamal::moss {

// Where the prior map and the trials come from: a world, or a CARMEN log.
struct ExperimentSource {
  std::string world = "CORRIDOR";  // a built-in name or a world file
  // A CARMEN log instead of a world: the map and the trials are cut from it
  // (carmen_trials.h; `train` and `test` are then the log's).
  std::string data;
  carmen::CarmenReadOptions read;  // how the log is read (carmen_log_flags.h)
  CarmenTrialsOptions log;
  int map_poses = 0, poses = 0;  // 0: the scenario's (M, N)
};

// How the L2G matches are made and weighed.
struct L2gMatching {
  ScanMatcherConfig matcher;  // the L2G matches' front end
  // sigma_d that the Censi information assumes; 0: the laser's range noise.
  double censi_sigma = 0.0;
  // Divide the L2G information by how overconfident the full map's matches
  // on the training trials are against the reference (their chi-square's
  // median over chi-square(3)'s, if above 1); needs references, so made for
  // logs and worlds alike, from training trials only.
  bool calibrate_information = false;
};

// What this process does of the run, with how many threads, into which folder.
struct ExperimentRun {
  int threads = 2;
  std::string out;  // directory
  // >= 0: run only MOSS climb `climb` for every C into <out>/climbs/, no
  // rows (one array task of a cluster run); a later run without it picks the
  // best of the finished climbs and writes the rows.
  int climb = -1;
  // Verify (or start) <out> against these parameters and stop: what a
  // cluster run does before it submits its climbs.
  bool verify_only = false;
};

struct ExperimentConfig {
  ExperimentSource source;
  std::vector<int> sizes;  // C values
  std::vector<std::string> methods = {"equidistant", "ssm", "moss"};
  int train = 10, test = 10;  // S, S'
  std::uint64_t seed = 1;
  int climbs = 10, steps = 1000;  // T, K
  bool reuse = true;              // MossConfig::reuse (same selections either way)
  LocalizerConfig localizer;
  L2gMatching matches;
  ExperimentRun run;
};

// Runs (or resumes) the experiment; progress lines go to `log`.
void runExperiment(const ExperimentConfig& config, const Registry& registry, std::ostream& log);

// "1-20", "6,11,16,21", "1-4,8": the C values.
std::vector<int> parseSizes(const std::string& text);

}  // namespace hamal::moss
