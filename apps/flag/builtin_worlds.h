// The built-in floor plans of FLAG's evaluation (thesis sec. 4.4.2):
//   office    corridors around two blocks, driven as a figure 8 of 180 m
//             (fig. 4.1), with door niches as corners, furniture (short and
//             tall), a cabinet in front of one corner and people walking past
//             corners;
//   corridor  a 100 m corridor with corners only at its ends and at three
//             niches 25 m apart, driven there and back, where FLAG coasts on
//             odometry between them.
// Labels are the corners moved by N(0, label_sigma^2 I) drawn from `seed`.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "apps/flag/floor_plan.h"

namespace hamal::flag {

std::vector<std::string> builtinWorldNames();
// The names, lower case; a name given is matched without regard to case
// (apps/common/builtin_name.h). Throws hamal::Error for an unknown name
// (listing the known ones).
FloorPlan builtinWorld(const std::string& name, double label_sigma, std::uint64_t seed);
// A built-in name, or else a floor-plan file.
FloorPlan loadWorld(const std::string& name_or_file, double label_sigma, std::uint64_t seed);

}  // namespace hamal::flag
