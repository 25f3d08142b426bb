// FlagRun: one localization run, a FlagLocalizer feeding a back-end named
// in the registry through the step runner (apps/bench/step_runner.h), graded
// against the truth (thesis sec. 4.4.2, figs. 4.1, 4.6, 4.11).
//
// Errors are those of the online estimate, each pose as the back-end
// estimated it right after that pose's step, which is what a robot
// localizing in real time has. Longitudinal and lateral errors are the
// position error in the true pose's frame (along and across the direction
// of travel), heading the wrapped angle error; all are mean absolute values
// over the run.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "apps/bench/step_runner.h"
#include "apps/flag/flag_localizer.h"
#include "apps/flag/floor_plan.h"
#include "apps/flag/simulator.h"
#include "core/backend.h"
#include "core/registry.h"

namespace hamal::flag {

struct RunErrors {
  double position = 0;       // mean |p_est - p_true|, m
  double longitudinal = 0;   // mean |along-track error|, m
  double lateral = 0;        // mean |cross-track error|, m
  double heading = 0;        // mean |theta error|, rad
  double last_position = 0;  // |p_est - p_true| at the last pose, m
};
RunErrors runErrors(const std::vector<Pose2>& estimate, const std::vector<Pose2>& truth);

struct FlagRun {
  std::vector<Pose2> truth;
  std::vector<Pose2> online;          // FLAG, each pose right after its step
  std::vector<Pose2> dead_reckoning;  // the start composed with the odometry
  // Per step: its time, and what the back-end's update was.
  struct Steps {
    std::vector<double> seconds;  // association + check + update, per step (wall clock)
    // The same on this thread's CPU clock: what the step costs, without the
    // time other processes take from it on a shared machine.
    std::vector<double> cpu_seconds;
    // Per step: what the back-end's update was, why, and its status.
    std::vector<apps::StepRow> rows;
  };
  Steps steps;
  AssociationStats stats;
  // The factors FLAG accepted.
  struct Factors {
    // Per step: the factors accepted so far, and how many of them are wrong.
    std::vector<std::size_t> so_far, wrong_so_far;
    // Max-mixture factors, and those of them whose null hypothesis is the
    // active component at the final estimate (switched off), and of those
    // the ones from the right corner.
    std::size_t mixtures = 0, null_active = 0, null_active_right = 0;
  };
  Factors factors;
  // Poses at which localization was lost (FlagLocalizer::lost), the first
  // of them (-1: never).
  struct Lost {
    std::size_t steps = 0;
    long first = -1;
  };
  Lost lost;
  RunErrors flag, odometry;
  Values final_estimate;
  bool ok = true;      // every update's status was ok and every estimate finite
  std::string status;  // why not: apps::RunOutcome::describe(), or a non-finite estimate
};

std::vector<LandmarkLabel> labelsOf(const FloorPlan& plan);

// What the back-end did over a run: how many steps were batches and which
// criterion called each, and the step times of batch and incremental steps
// apart, so a reader sees where the run's p99 comes from.
struct UpdateSummary {
  std::size_t steps = 0, batch = 0, incremental = 0;
  // Incremental steps in which some factor switched mode (a max-mixture
  // turned to or from its null hypothesis), which relinearises and
  // refactors its variables: AprilSAM says so in the reason.
  std::size_t mode_switches = 0;
  // Batch steps per criterion (reasonCriterion), most frequent first.
  std::vector<std::pair<std::string, std::size_t>> batch_reasons;
  std::vector<double> batch_cpu_seconds, incremental_cpu_seconds;
};
UpdateSummary summarizeUpdates(const FlagRun& run);

// A back-end's reason without the numbers that change each step, so that
// equal criteria count together: "|L|=120 >= NL_T=100" -> "|L| >= NL_T",
// "incremental cost x n_lc >= batch cost (3 x 1 >= 2)" -> "incremental
// cost x n_lc >= batch cost"; what follows "; " (what happened after the
// decision) is left out.
std::string reasonCriterion(const std::string& reason);

// Runs FLAG over `recording` (start pose from the recording's first truth
// pose, as the thesis' runs start at a known spot).
FlagRun runFlag(const std::vector<LandmarkLabel>& labels, const Recording& recording,
                const FlagOptions& options, const Registry& registry);

}  // namespace hamal::flag
