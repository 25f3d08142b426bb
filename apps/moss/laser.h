// Laser: the simulated 2D range finder of thesis sec. 5.5 (360 degree field
// of view, 4 m range, range noise sigma_d = 2 cm) by ray casting against the
// world's walls and a trial's obstacles.
//
// Beams: 180 (every 2 degrees), enough for point-to-line matching to see a
// wall end or an opening of a few decimetres at 4 m, and cheap to cast.
// Beams that hit nothing within range return no point (as a real scanner's
// max-range readings are dropped).
#pragma once

#include <random>
#include <vector>

#include "apps/moss/world.h"

namespace hamal::moss {

struct LaserConfig {
  int beams = 180;
  double max_range = 4.0;     // m
  double sigma_range = 0.02;  // m, sigma_d
};

// A scan's returns as points in the sensor (robot) frame.
using Scan = std::vector<Point2>;

class Laser {
 public:
  explicit Laser(LaserConfig config = {});
  const LaserConfig& config() const { return config_; }
  // Casts every beam from `pose` against `walls` and `obstacles`; range noise
  // is drawn from `rng` (pass nullptr for exact ranges).
  Scan scan(const Pose2& pose, const std::vector<Segment>& walls,
            const std::vector<Segment>& obstacles, std::mt19937_64* rng) const;
  // The exact range of each beam (max_range where nothing is hit).
  std::vector<double> ranges(const Pose2& pose, const std::vector<Segment>& walls,
                             const std::vector<Segment>& obstacles) const;

 private:
  LaserConfig config_;
};

}  // namespace hamal::moss
