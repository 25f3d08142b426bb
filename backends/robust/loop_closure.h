// isLoopClosure: which factors the robust models treat as candidates (may be
// false) and which as known inliers. As in Vertigo and Olson & Agarwal, a
// factor between two poses whose ids differ by one is odometry, always kept;
// any other factor between two poses is a loop closure, which may be false.
// Factors on landmarks are neither (they are left as they are).
#pragma once

#include "core/factor.h"

namespace hamal::robust {

// Two pose keys whose ids differ by more than one.
inline bool isLoopClosure(const Factor& factor) {
  const auto& keys = factor.keys();
  if (keys.size() != 2 || keys[0].kind() != kPoseKind || keys[1].kind() != kPoseKind) return false;
  const auto a = keys[0].index(), b = keys[1].index();
  return (a > b ? a - b : b - a) > 1;
}

}  // namespace hamal::robust
