// AprilSamOptions: see aprilsam_options.h (thesis ch. 3).
#include "backends/aprilsam/aprilsam_options.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "core/error.h"

namespace hamal::aprilsam {

namespace {
// The option values, in the order of AprilSamOptions' enums.
const std::vector<std::string> kOrderings = {"minheap", "bhamd", "amd", "natural"};
const std::vector<std::string> kBacksolves = {"partial", "full"};
const std::vector<std::string> kFactorUpdates = {"rank", "refactor"};
const std::vector<std::string> kReeliminates = {"full", "top"};

template <typename Enum>
Enum choice(const Options& o, const std::string& name, const std::vector<std::string>& names) {
  const std::string value = o.getChoice(name, names);
  return static_cast<Enum>(std::find(names.begin(), names.end(), value) - names.begin());
}
template <typename Enum>
const std::string& name(Enum value, const std::vector<std::string>& names) {
  return names.at(static_cast<std::size_t>(value));
}

// Shortest round-tripping form: std::to_string's fixed six decimals would
// turn 1e-9 into "0", and the listed default is the value the back-end gets.
std::string num(double v) {
  std::ostringstream os;
  for (int prec = 1;; ++prec) {
    os.str("");
    os << std::setprecision(prec) << v;
    if (prec >= 17 || std::stod(os.str()) == v) return os.str();
  }
}
}  // namespace

std::vector<OptionSpec> AprilSamOptions::optionSpecs() {
  const AprilSamOptions d;
  std::vector<OptionSpec> specs = UpdatePolicy::optionSpecs();
  specs.push_back({"ordering", name(d.ordering, kOrderings),
                   "batch ordering (sec. 3.4.3): minheap (Alg. 3.2, score eq. 3.20), bhamd "
                   "(newest node last, BHAMD on the rest: AprilSAM-NoPredictiveOrder), amd "
                   "(SuiteSparse AMD), natural (order of arrival)"});
  specs.push_back(
      {"loop_closure_radius", num(d.loop_closure_radius),
       "R_T (eq. 3.20), metres: nodes within it of the newest pose are ordered "
       "last by minheap and, with n_lc=0, counted as n_lc (COUNTPOSSIBLELOOPCLOSURENODES, "
       "Alg. 3.1 line 9) by the time criterion. The thesis gives no value"});
  specs.push_back({"n_lc", std::to_string(d.n_lc),
                   "n_lc of the time criterion (Alg. 3.1 line 10): 0 counts the nodes within "
                   "R_T of the newest pose, as the thesis states it; a positive value fixes it, "
                   "as the reference implementation does (3). Counting finds many nodes in "
                   "revisited areas, so the time criterion then batches at almost every loop "
                   "closure"});
  specs.push_back(
      {"factor_update", name(d.factor_update, kFactorUpdates),
       "how an incremental step updates R on the affected rows (the same rows, the same R~ "
       "to rounding): rank (Householder reflections of the new Jacobian rows into R, O(k w) "
       "for a row of width w and k new rows) or refactor (form R_aff^T R_aff + A_new and "
       "factor it, eq. 3.14 as the thesis writes it, O(w^2) per row)"});
  specs.push_back({"rank_update_max_rows", std::to_string(d.rank_update_max_rows),
                   "with factor_update=rank, a step with more new Jacobian rows than this is "
                   "refactored instead (the reflections' cost grows with the rows)"});
  specs.push_back({"backsolve", name(d.backsolve.kind, kBacksolves),
                   "back-substitution (sec. 3.4.2, fig. 3.7): partial (only the rows an "
                   "update changes) or full (every row: AprilSAM-FullSolve)"});
  specs.push_back(
      {"backsolve_tolerance",
       num(d.backsolve.tolerance),
       "partial back-substitution: propagate a change of dx_k to the rows below "
       "only when it exceeds this (inf-norm), as GTSAM's wildfire threshold (also "
       "1e-3). 0 = exact, bit for bit the full solve; a larger value skips more small "
       "changes, trading a little accuracy for time (the closing verdict solves every row at "
       "the end of a run)",
       {"backsolve_tol"}});
  specs.push_back(
      {"batch_first", d.batch_first ? "true" : "false",
       "ask the criteria that do not depend on the step's solve (the time criterion, with "
       "the flops the rank update would report, computed from the structure; the periodic "
       "one) before the incremental update, and batch without it when they are met. Alg. "
       "3.1 updates first; skipping that update, which the batch refactors away, takes a "
       "quarter off a batch step, but the batch then starts from the estimate before it, "
       "so the run differs (factor_update=rank and the deterministic cost only). With "
       "reeliminate=top the time criterion re-eliminates the top there instead"});
  specs.push_back({"batch_iterations", std::to_string(d.batch.iterations),
                   "Gauss-Newton steps per batch update (Alg. 3.1 lines 12-16 and the "
                   "reference code take 1)"});
  specs.push_back({"damping", num(d.batch.damping),
                   "lambda of the Levenberg-damped batch (A_ii += lambda diag(A_ii)) used "
                   "when a factorisation meets a block that is not positive definite"});
  specs.push_back(DormantPolicy::optionSpec());
  specs.push_back(
      {"reeliminate", name(d.reeliminate, kReeliminates),
       "what a batch decision of the policy re-eliminates: full (Alg. 3.1 lines 12-16: "
       "every variable relinearised, reordered, refactored) or top (iSAM2's way: only the "
       "rows the factors added since the last re-elimination and the variables in L reach, "
       "with their ancestors, reordered by minheap and refactored from the factors and the "
       "kept rows' marginals; the top's variables move to the estimate unless a factor ties "
       "them to a kept row). top falls back to full for factors with modes, after a damped "
       "batch, or when the top is more than top_share of R; it needs ordering=minheap"});
  specs.push_back(
      {"top_relinearize", num(d.top.relinearize),
       "reeliminate=top: the top is taken from the variables whose change |dx_i| (2-norm) "
       "reaches this fraction of delta_T, besides those in L (1: L alone, iSAM2's rule). "
       "With L alone a variable that settles just below delta_T is never relinearised, "
       "which a full batch would do"});
  specs.push_back({"top_share", num(d.top.share),
                   "reeliminate=top: a top of more than this share of R's rows is re-eliminated "
                   "by a full batch instead (which also relinearises and reorders the rest)"});
  specs.push_back({"top_backoff", std::to_string(d.top.backoff),
                   "reeliminate=top: after three full batches in a row for tops over top_share "
                   "that each left L no smaller (no Gauss-Newton progress), the next such tops "
                   "stay incremental for 2, 4, 8... updates, at most this many "
                   "(backends/aprilsam/top_backoff.h); 0: a batch at every one"});
  return specs;
}

AprilSamOptions AprilSamOptions::fromOptions(const Options& o) {
  AprilSamOptions a;
  a.policy = UpdatePolicy::fromOptions(o);
  a.ordering = choice<AprilSamOptions::Ordering>(o, "ordering", kOrderings);
  a.loop_closure_radius = o.getDouble("loop_closure_radius");
  a.n_lc = o.getInt("n_lc");
  a.factor_update = choice<AprilSamOptions::FactorUpdate>(o, "factor_update", kFactorUpdates);
  a.rank_update_max_rows = o.getInt("rank_update_max_rows");
  a.backsolve.kind = choice<AprilSamOptions::Backsolve>(o, "backsolve", kBacksolves);
  a.backsolve.tolerance = o.getDouble("backsolve_tolerance");
  a.batch.iterations = o.getInt("batch_iterations");
  a.batch_first = o.getBool("batch_first");
  a.batch.damping = o.getDouble("damping");
  a.dormant_scale = DormantPolicy::fromOptions(o, "aprilsam").scale();
  a.reeliminate = choice<AprilSamOptions::Reeliminate>(o, "reeliminate", kReeliminates);
  a.top.share = o.getDouble("top_share");
  a.top.relinearize = o.getDouble("top_relinearize");
  a.top.backoff = o.getInt("top_backoff");
  const std::string who = o.owner().empty() ? "aprilsam" : o.owner();
  if (!(a.loop_closure_radius >= 0) || !std::isfinite(a.loop_closure_radius))
    throw Error(who + ": option loop_closure_radius must be a finite number >= 0");
  if (a.n_lc < 0) throw Error(who + ": option n_lc must be >= 0");
  if (!(a.backsolve.tolerance >= 0) || !std::isfinite(a.backsolve.tolerance))
    throw Error(who + ": option backsolve_tolerance must be a finite number >= 0");
  if (a.rank_update_max_rows < 0) throw Error(who + ": option rank_update_max_rows must be >= 0");
  if (a.batch.iterations < 1) throw Error(who + ": option batch_iterations must be >= 1");
  if (!(a.batch.damping > 0) || !std::isfinite(a.batch.damping))
    throw Error(who + ": option damping must be a finite number > 0");
  if (!(a.top.relinearize > 0 && a.top.relinearize <= 1))
    throw Error(who + ": option top_relinearize must be a number in (0, 1]");
  if (!(a.top.share >= 0 && a.top.share <= 1))
    throw Error(who + ": option top_share must be a number in [0, 1]");
  if (a.top.backoff < 0) throw Error(who + ": option top_backoff must be >= 0");
  if (a.reeliminate == Reeliminate::kTop && a.ordering != Ordering::kMinHeap)
    throw Error(who +
                ": option reeliminate=top needs ordering=minheap (the top is reordered "
                "by the min-heap ordering)");
  return a;
}

}  // namespace hamal::aprilsam
