// Percentiles: see percentiles.h.
#include "apps/bench/percentiles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"

namespace hamal::apps {

double percentile(std::vector<double> samples, double p) {
  if (!(p >= 0.0 && p <= 100.0))
    throw Error("percentile " + std::to_string(p) + " is not in [0, 100]");
  if (samples.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(samples.begin(), samples.end());
  const double h = (samples.size() - 1) * p / 100.0;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, samples.size() - 1);
  return samples[lo] + (h - lo) * (samples[hi] - samples[lo]);
}

double median(std::vector<double> samples) { return percentile(std::move(samples), 50.0); }

double shareBelow(const std::vector<double>& samples, double bound) {
  if (samples.empty()) return 0.0;
  const auto n = std::count_if(samples.begin(), samples.end(), [&](double s) { return s < bound; });
  return double(n) / double(samples.size());
}

}  // namespace hamal::apps
