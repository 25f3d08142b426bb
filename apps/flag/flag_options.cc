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
  positive(landmarks.sigma, "landmark sigma");
  positive(association.gate, "gate");
  positive(association.gate_sigmas, "gate sigmas");
  positive(odometry.scale, "odometry scale");
  positive(consistency.threshold, "consistency threshold");
  positive(start.sigma_xy, "start sigma xy");
  positive(start.sigma_theta, "start sigma theta");
  if (consistency.min_links < 1) throw Error("min_links must be >= 1");
  if (consistency.window < 1) throw Error("window must be >= 1");
  if (!(consistency.sigmas >= 0) || !std::isfinite(consistency.sigmas))
    throw Error("consistency sigmas must be >= 0 and finite");
  if (!(odometry.jitter_xy >= 0 && odometry.jitter_theta >= 0) ||
      !std::isfinite(odometry.jitter_xy) || !std::isfinite(odometry.jitter_theta) ||
      ((odometry.jitter_xy > 0) != (odometry.jitter_theta > 0)))
    throw Error("odometry jitter sigmas must be finite and both 0 (off) or both > 0");
  if (!(association.max_gate_sigma >= 0) || !std::isfinite(association.max_gate_sigma))
    throw Error("max gate sigma must be >= 0 and finite");
  if (!(association.wall_sigma >= 0) || !std::isfinite(association.wall_sigma))
    throw Error("wall sigma must be >= 0 and finite");
  if (lost.after < 1) throw Error("lost_after must be >= 1");
  positive(lost.sigma, "lost sigma");
  const std::string null_problem = MaxMixtureFactor::nullHypothesisProblem(
      max_mixture.null_weight, max_mixture.null_scale, "--null_weight", "--null_scale");
  if (!null_problem.empty()) throw Error(null_problem);
  if (backend.empty()) throw Error("backend must be named");
}

}  // namespace hamal::flag
