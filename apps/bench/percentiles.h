// Percentiles of per-step times (docs/PROTOCOL.md, "The thesis protocol",
// item 4: per-step p50 / p90 / p99 / max, and the share of steps under a bound).
//
// Linear interpolation between closest ranks (numpy's default, "type 7"):
// for sorted x_0..x_{n-1}, the p-th percentile is at rank h = (n-1) p / 100,
// x_floor(h) + (h - floor(h)) (x_floor(h)+1 - x_floor(h)). p50 of an even count
// is the mean of the middle two; p100 is the max; p0 the min.
#pragma once

#include <vector>

namespace hamal::apps {

// p in [0, 100]; NaN for an empty sample. Throws hamal::Error for p outside.
double percentile(std::vector<double> samples, double p);
double median(std::vector<double> samples);
// Fraction (0..1) of samples strictly below `bound`; 0 for an empty sample.
double shareBelow(const std::vector<double>& samples, double bound);

}  // namespace hamal::apps
