// FlagRun: one localization run, a FlagLocalizer feeding a back-end named
// in the registry, step by step, graded against the truth (thesis sec. 4.4.2,
// figs. 4.1, 4.6, 4.11).
//
// Errors are those of the online estimate, each pose as the back-end
// estimated it right after that pose's step, which is what a robot
// localizing in real time has. Longitudinal and lateral errors are the
// position error in the true pose's frame (along and across the direction
// of travel), heading the wrapped angle error; all are mean absolute values
// over the run.
#pragma once
#include <string>
#include <vector>

#include "apps/flag/flag_localizer.h"
#include "apps/flag/floor_plan.h"
#include "apps/flag/simulator.h"
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

struct RunResult {
  std::vector<Pose2> truth;
  std::vector<Pose2> online;          // FLAG, each pose right after its step
  std::vector<Pose2> dead_reckoning;  // the start composed with the odometry
  std::vector<double> step_seconds;   // association + check + update, per step (wall clock)
  // The same on this thread's CPU clock: what the step costs, without the
  // time other processes take from it on a shared machine.
  std::vector<double> step_cpu_seconds;
  AssociationStats stats;
  // Per step: the factors accepted so far, and how many of them are wrong.
  std::vector<std::size_t> factors_so_far, wrong_so_far;
  // Max-mixture factors, and those of them whose null hypothesis is the
  // active component at the final estimate (switched off).
  std::size_t mixtures = 0, null_active = 0;
  RunErrors flag, odometry;
  Values final_estimate;
  bool ok = true;      // every update's status was ok
  std::string status;  // the first failing update's message
};

std::vector<LandmarkLabel> labelsOf(const FloorPlan& plan);

// Runs FLAG over `recording` (start pose from the recording's first truth
// pose, as the thesis' runs start at a known spot).
RunResult runFlag(const std::vector<LandmarkLabel>& labels, const Recording& recording,
                  const FlagOptions& options, const Registry& registry);

}  // namespace hamal::flag
