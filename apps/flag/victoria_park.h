// FLAG on real data: Victoria Park (GTSAM's victoria_park.txt: a car's
// odometry and its detections of trees, with the trees' ids).
//
// The "floor plan" is made from the known-association solution: the file's
// graph run through the thesis protocol on a back-end (AprilSAM), whose
// landmark estimates, moved by N(0, label_sigma^2 I), are the labels, and
// whose poses are the reference trajectory. FLAG then localizes against
// those labels with the ids hidden (nearest-neighbour association, the
// pairwise check, the max-mixtures), incrementally, and is graded by
// association precision and recall against the file's ids and by the ATE
// of its trajectory against the reference. The same pipeline with the ids
// given (known_association) is the known-association baseline.
//
// Detections are the file's LANDMARK points (robot frame, covariance
// sigma^2 I) as range and bearing with range sigma = sigma and bearing
// sigma = sigma / range; odometry keeps the file's sigmas.
#pragma once
#include <string>
#include <vector>

#include "apps/flag/flag_localizer.h"
#include "apps/flag/simulator.h"
#include "core/registry.h"

namespace hamal::flag {

struct VictoriaPark {
  Recording recording;  // truth = the reference trajectory
  std::vector<LandmarkLabel> labels;
  Values reference_landmarks;    // L(id): the known-association solution's trees
  double reference_seconds = 0;  // time to make the reference
};

// Throws hamal::Error for a file that cannot be read (file, line, reason)
// or whose odometry is not one chain.
VictoriaPark prepareVictoriaPark(const std::string& path, const Registry& registry,
                                 const std::string& backend, double label_sigma,
                                 std::uint64_t seed);

}  // namespace hamal::flag
