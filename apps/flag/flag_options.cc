// FlagOptions' checks (flag_options.h).
#include "apps/flag/flag_options.h"

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "factors/max_mixture_factor.h"

namespace hamal::flag {

void FlagOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) {
      std::ostringstream got;
      got << v;
      throw Error(std::string(name) + " must be > 0 and finite, got " + got.str());
    }
  };
  positive(landmark_sigma, "landmark sigma");
  positive(gate, "gate");
  positive(gate_sigmas, "gate sigmas");
  positive(odometry_scale, "odometry scale");
  positive(consistency_threshold, "consistency threshold");
  positive(start_sigma_xy, "start sigma xy");
  positive(start_sigma_theta, "start sigma theta");
  if (min_links < 1) throw Error("min_links must be >= 1");
  if (window < 1) throw Error("window must be >= 1");
  if (!(consistency_sigmas >= 0) || !std::isfinite(consistency_sigmas))
    throw Error("consistency sigmas must be >= 0 and finite");
  if (!(odometry_jitter_xy >= 0 && odometry_jitter_theta >= 0) ||
      !std::isfinite(odometry_jitter_xy) || !std::isfinite(odometry_jitter_theta) ||
      ((odometry_jitter_xy > 0) != (odometry_jitter_theta > 0)))
    throw Error("odometry jitter sigmas must be finite and both 0 (off) or both > 0");
  if (!(max_gate_sigma >= 0) || !std::isfinite(max_gate_sigma))
    throw Error("max gate sigma must be >= 0 and finite");
  if (lost_after < 1) throw Error("lost_after must be >= 1");
  positive(lost_sigma, "lost sigma");
  const std::string null_problem = MaxMixtureFactor::nullHypothesisProblem(
      null_weight, null_scale, "--null_weight", "--null_scale");
  if (!null_problem.empty()) throw Error(null_problem);
  if (backend.empty()) throw Error("backend must be named");
}

}  // namespace hamal::flag
