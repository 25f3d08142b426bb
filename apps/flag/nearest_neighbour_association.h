// NearestNeighbourAssociation: a detection to the landmark nearest to where
// it projects, within a gate (thesis sec. 4.3.3: the max-mixtures are
// "bootstrapped with nearest-neighbor associations"; sec. 4.4.3.1: 50 cm).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>
#include "core/pose2.h"

namespace hamal::flag {

class NearestNeighbourAssociation {
 public:
  explicit NearestNeighbourAssociation(double gate) : gate_(gate) {}
  // `landmarks[k]` is where landmark `ids[k]` is believed to be now.
  // Returns the index k of the nearest one within the gate of `point`.
  std::optional<std::size_t> associate(const Point2& point,
                                       const std::vector<Point2>& landmarks) const;
  double gate() const { return gate_; }

 private:
  double gate_;
};

// Where a range-bearing detection from `pose` lies in the world.
Point2 project(const Pose2& pose, double range, double bearing);

}  // namespace hamal::flag
