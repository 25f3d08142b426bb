// AprilSAM's incremental-vs-batch decision (thesis sec. 3.4.4, Alg. 3.1) and
// the periodic policy; see the header for the conventions.
#include "backends/aprilsam/update_policy.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>
#include <utility>

#include "core/error.h"

namespace hamal::aprilsam {
namespace {

// In the enums' order.
const std::vector<std::string> kModes = {"adaptive", "periodic", "incremental"};
const std::vector<std::string> kCosts = {"deterministic", "wallclock"};

template <typename Enum>
Enum choice(const Options& o, const std::string& name, const std::vector<std::string>& names) {
  const std::string value = o.getChoice(name, names);
  return static_cast<Enum>(std::find(names.begin(), names.end(), value) - names.begin());
}

// As `std::ostream << v` prints it (%g), without a stream or printf: an
// incremental step formats its reason every update, and a stream's
// construction, or printf's exact decimal conversion, costs more than the
// rest of a small step's decision. to_chars with a precision is specified
// to give printf's digits.
std::string str(double v) {
  char buffer[32];
  const std::to_chars_result r =
      std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 6);
  return std::string(buffer, r.ec == std::errc() ? r.ptr : buffer);
}

// Throws on the first option out of its range, naming it as the registry does.
void validate(const UpdatePolicyOptions& o) {
  auto fail = [](const std::string& what) { throw Error("aprilsam: option " + what); };
  if (o.period < 1) fail("period=" + std::to_string(o.period) + " must be >= 1");
  if (!(o.delta_t >= 0) || !std::isfinite(o.delta_t)) {
    fail("delta_t=" + str(o.delta_t) + " must be finite and >= 0");
  }
  if (o.nl_t < 1) fail("nl_t=" + std::to_string(o.nl_t) + " must be >= 1");
  if (!(o.big_delta_t > 0)) fail("big_delta_t=" + str(o.big_delta_t) + " must be > 0");
}

}  // namespace

const char* toString(UpdatePolicyOptions::Mode mode) {
  return kModes.at(static_cast<std::size_t>(mode)).c_str();
}
const char* toString(UpdatePolicyOptions::Cost cost) {
  return kCosts.at(static_cast<std::size_t>(cost)).c_str();
}

UpdatePolicy::UpdatePolicy(UpdatePolicyOptions options) : options_(std::move(options)) {
  validate(options_);
}

UpdateDecision UpdatePolicy::decide(long step, long moved_nodes, double dx_norm,
                                    const UpdateCosts& costs) const {
  if (step <= 0) return {true, "first update"};
  using Mode = UpdatePolicyOptions::Mode;
  if (options_.mode == Mode::kIncremental) return {false, "incremental mode"};
  if (options_.mode == Mode::kPeriodic) {
    if (step % options_.period == 0) return {true, "periodic k=" + std::to_string(options_.period)};
    return {false, "periodic k=" + std::to_string(options_.period) + ", step " +
                       std::to_string(step) + " between batches"};
  }
  // Alg. 3.1 line 10, criteria in the thesis' order of sec. 3.4.4.
  if (moved_nodes >= options_.nl_t) {
    return {true,
            "|L|=" + std::to_string(moved_nodes) + " >= NL_T=" + std::to_string(options_.nl_t)};
  }
  if (!(dx_norm < options_.big_delta_t)) {
    return {true, "||dx||=" + str(dx_norm) + " >= Delta_T=" + str(options_.big_delta_t)};
  }
  const double predicted =
      costs.incremental * static_cast<double>(costs.possible_loop_closure_nodes);
  if (costs.batch > 0 && predicted >= costs.batch) {
    return {true, "incremental cost x n_lc >= batch cost (" + str(costs.incremental) + " x " +
                      std::to_string(costs.possible_loop_closure_nodes) +
                      " >= " + str(costs.batch) + ")"};
  }
  return {false,
          "no criterion met: |L|=" + std::to_string(moved_nodes) + ", ||dx||=" + str(dx_norm) +
              ", incremental cost x n_lc=" + str(predicted) +
              (costs.batch > 0 ? " < batch cost " + str(costs.batch) : " (no batch cost yet)")};
}

std::vector<OptionSpec> UpdatePolicy::optionSpecs() {
  const UpdatePolicyOptions d;
  return {
      {"mode", toString(d.mode),
       "batch decision: adaptive (Alg. 3.1: the three criteria), periodic (batch every "
       "`period` steps, AprilSAM-Periodic), incremental (batch only at the first update)"},
      {"period", std::to_string(d.period),
       "k: steps between batches in periodic mode. Up to k-1 steps run on old "
       "linearisations, so a smaller k ends nearer the batch optimum (sec. 3.5.2: periodic "
       "is less accurate); the thesis compared with 50 (M3500) and 100 (W10000)"},
      {"delta_t", str(d.delta_t),
       "delta_T: a node whose change |dx_i| (inf-norm of its block) reaches it joins L. "
       "0.1 is GTSAM iSAM2's default relinearisation threshold (the parameter the thesis "
       "sets delta_T equal to in fig. 3.8d) and the reference demo's value; a smaller "
       "value batches more often"},
      {"nl_t", std::to_string(d.nl_t), "NL_T: batch when |L| >= NL_T nodes"},
      {"big_delta_t", str(d.big_delta_t),
       "Delta_T: batch when the state change ||dx|| (2-norm) >= Delta_T (the reference "
       "implementation lacks this criterion)"},
      {"cost", toString(d.cost),
       "costs compared by the time criterion (RUNTIME(incremental) x n_lc >= "
       "RUNTIME(batch)): deterministic (predicted flops, reproducible) or wallclock (measured "
       "seconds, as the thesis)"},
  };
}

UpdatePolicyOptions UpdatePolicy::fromOptions(const Options& o) {
  UpdatePolicyOptions p;
  p.mode = choice<UpdatePolicyOptions::Mode>(o, "mode", kModes);
  p.period = o.getInt("period");
  p.delta_t = o.getDouble("delta_t");
  p.nl_t = o.getInt("nl_t");
  p.big_delta_t = o.getDouble("big_delta_t");
  p.cost = choice<UpdatePolicyOptions::Cost>(o, "cost", kCosts);
  validate(p);
  return p;
}

}  // namespace hamal::aprilsam
