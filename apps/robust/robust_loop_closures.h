// RobustLoopClosures: the models the robust benchmark compares on the loop
// closures of a pose graph (apps/robust/README.md): plain least squares,
// Ceres' Cauchy and Huber losses, dynamic covariance scaling (Agarwal et
// al., ICRA 2013), max-mixtures (Olson & Agarwal, RSS 2012;
// factors/max_mixture_factor.h, the model FLAG builds on, thesis ch. 4) and
// graduated non-convexity with a truncated-least-squares or Geman-McClure
// loss (Yang et al., RA-L 2020; backends/robust/graduated_non_convexity.h).
// Odometry (poses whose ids differ by one) is left as it is, as Vertigo and
// Olson & Agarwal leave it: only loop closures can be false
// (backends/robust/loop_closure.h).
//
// The model is picked by options of the back-end spec that hamal_robust
// runs, so the sweep runner treats "aprilsam:robust=gnc" like any spec:
//   robust=none|cauchy|huber|dcs|maxmix|gnc-tls|gnc-gm|gnc|pcm|pcm+gnc
//                    (default none; gnc is gnc-tls; pcm is pairwise
//                    consistency maximisation, Mangelson et al. ICRA 2018,
//                    as a front end, then least squares or gnc-tls)
//   loss_scale=1     a of CauchyLoss(a) / HuberLoss(a), on the whitened
//                    residual: edges beyond about a sigmas are down-weighted
//   dcs_phi=1        Phi of DCS (the paper's default)
//   null_weight=0.01 max-mixture null hypothesis weight, Vertigo's default
//   null_scale=1e-12 its information scale; with 0.01 the null component
//                    wins beyond chi2 = 2 ln(0.99/0.01) + 3 ln(1e12) ~ 92.1
//                    (a 3-dof edge further out than ~9.6 sigma)
//   maxmix_start=map where max-mixtures start (backends/robust/
//                    max_mixture_start.h): map (a batch from GNC's estimate,
//                    a new pose guessed from a closure that agrees with the
//                    estimate) or odometry (the guesses as given)
//   gnc_*            GraduatedNonConvexity's options (GncOptions)
//   pcm_*            PCM's options (pcmOptionSpecs)
// The losses and max-mixtures change the factors (applyRobustMethod); GNC
// and PCM wrap the back-end (robustRegistry), in batch and incrementally
// alike.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "core/factor.h"
#include "core/options.h"
#include "core/registry.h"
#include "core/values.h"

namespace hamal::apps {

enum class RobustMethod {
  kLeastSquares,
  kCauchy,
  kHuber,
  kDcs,
  kMaxMixture,
  kGncTls,
  kGncGm,
  kPcm,
  kPcmGnc
};
// "none" | "cauchy" | "huber" | "dcs" | "maxmix" | "gnc-tls" | "gnc-gm" |
// "gnc" (= gnc-tls) | "pcm" | "pcm+gnc"; throws hamal::Error otherwise.
RobustMethod parseRobustMethod(const std::string& name);
const char* robustMethodName(RobustMethod method);
bool isGnc(RobustMethod method);  // gnc-tls, gnc-gm, pcm+gnc
bool isPcm(RobustMethod method);  // pcm, pcm+gnc
// The losses and max-mixtures, which applyRobustMethod puts on the loop
// closures' factors; the others decide in the back-end.
bool changesFactors(RobustMethod method);

struct RobustOptions {
  RobustMethod method = RobustMethod::kLeastSquares;
  double loss_scale = 1;
  double dcs_phi = 1;
  double null_weight = 0.01;
  double null_scale = 1e-12;
  bool maxmix_start_at_map = true;  // maxmix_start=map
  robust::GncOptions gnc;
  robust::PcmOptions pcm;
};

// The option names above with their defaults and help.
std::vector<OptionSpec> robustOptionSpecs();
// Reads them from a resolved Options (throws hamal::Error on a bad value).
RobustOptions robustOptionsFrom(const Options& options);

// The chi2 of a `dimension`-dof closure beyond which the null hypothesis of
// a (null_weight, null_scale) max-mixture wins (92.1 for 0.01, 1e-12, 3):
// where MaxMixtureStart lets a closure that agrees with the map guess a pose.
double nullHypothesisCrossover(double null_weight, double null_scale, int dimension);

// A registry with `base`'s factor kinds and every back-end of `base` taking
// robustOptionSpecs() on top of its own options; its factories drop them
// before making the base back-end, and wrap it in GraduatedNonConvexity for
// the GNC models. So a spec "ceres:robust=huber,max_iterations=50" resolves,
// lists (--list-backends) and runs like any other.
Registry robustRegistry(const Registry& base);

using robust::isLoopClosure;

// `factors` with the method on every loop closure: the same factor objects
// for least squares, GNC (which weighs them in the back-end) and for
// odometry; for the losses (DCS too), a copy of each loop
// closure (a BetweenFactor, else hamal::Error) carrying the loss; for
// max-mixtures, MaxMixtureFactor::withNullHypothesis around each. The input
// factors are never changed.
std::vector<FactorPtr> applyRobustMethod(const std::vector<FactorPtr>& factors,
                                         const RobustOptions& options);

// Whether the null hypothesis of a (null_weight, null_scale) max-mixture
// around `factor` is the active component at `values`: "switched off".
// For max-mixture runs it is exactly what the solver used; for the other
// models it says which edges the same rule would reject at their estimate.
bool nullHypothesisActive(const FactorPtr& factor, const Values& values,
                          const RobustOptions& options);

}  // namespace hamal::apps
