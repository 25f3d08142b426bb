// GraduatedNonConvexity: robust estimation by graduated non-convexity (Yang,
// Antonante, Tzoumas, Carlone, "Graduated Non-Convexity for Robust Spatial
// Perception: From Non-Minimal Solvers to Global Outlier Rejection", RA-L
// 2020) over any back-end, in batch and incrementally (in the spirit of
// riSAM: McGann, Rogers, Kaess, "Robust Incremental Smoothing and Mapping",
// ICRA 2023).
//
// Some factors are candidates (loop closures, picked by a predicate) whose
// weights are annealed from least squares towards truncated least squares
// or Geman-McClure; every other factor keeps weight 1. The weights reach
// the inner back-end through FactorWeights (core/factor_weights.h) where it
// offers it, else through RebuiltFactorWeights (rebuilt_factor_weights.h).
// An update that converged is ok only if no doubt rule fires
// (answer_doubt.h). The method, the rules that decide a step's candidates
// incrementally and the doubt rules, each with the measurement behind it,
// are described once in docs/ROBUST_RULES.md (the doubt rules in
// docs/ROBUST_DOUBT_RULES.md).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "backends/robust/near_misses.h"
#include "core/backend.h"
#include "core/closing_verdict.h"
#include "core/factor.h"
#include "core/factor_weights.h"
#include "core/options.h"

namespace hamal::robust {

class TruncatedObjectiveCheck;

struct GncOptions {
  enum class Loss { kTruncatedLeastSquares, kGemanMcClure };
  Loss loss = Loss::kTruncatedLeastSquares;
  double inlier_probability = 0.99;  // c2 = chi2 quantile of the residual dimension
  double inlier_threshold = 0;       // c2 itself when > 0 (overrides the probability)
  double mu_step = 1.4;
  long max_iterations = 100;
  double weight_tolerance = 1e-4;
  double cost_tolerance = 1e-5;
  long linear_limit = 16;  // most candidates annealed on the factorisation
  // The doubt rules (answer_doubt.h): off, report an answer in doubt as
  // kUncertain, or adopt a better alternative first (docs/ROBUST_DOUBT_RULES.md).
  enum class Doubt { kOff, kReport, kAdopt };
  Doubt doubt = Doubt::kAdopt;
  // At the end of a run (closingVerdict) a cheaper alternative is reported
  // (kReport), or, with doubt kAdopt, adopted and checked again (kAdopt).
  // Report by default: on the tuning worlds adopting there lost right
  // answers (backends/robust/DOUBT.md).
  Doubt closing = Doubt::kReport;
  // Where the answer shows the stated noise overstated (noise_scale.h), at
  // the end of a run: the noise scale's cheaper alternative is reported
  // (kReport), or, with doubt kAdopt, taken and checked again, a plain
  // alternative then doubt only if it is cheaper at the scaled c2 too
  // (kAdopt): the stated c2 lets a false group bent within it cost less
  // than the clean map (backends/robust/NOISE_SCALE.md).
  Doubt noise_scale = Doubt::kAdopt;
  // Where an answer is in doubt (flips or most closures rejected), its
  // alternatives include the consistent group (consistent_group.h): least
  // squares over the largest set of closures the odometry says agree, from
  // the answer, then polished like the others; and the run's closing
  // verdict first catches up on the closures since the last check, so the
  // verdict covers every closure (closingVerdict). Off by default: it turns
  // wrong answers in doubt into TLS minima that the stated c2 prefers to
  // the truth on some judging graphs (backends/robust/DOUBT.md).
  bool consistent_group = false;

  // The options above as back-end options ("gnc_probability", ...), with
  // GTSAM's GncParams defaults, and their parsing (hamal::Error naming the
  // option and the range it must be in).
  static std::vector<OptionSpec> optionSpecs();
  static GncOptions fromOptions(const Options& options, Loss loss);
  // c2 of a candidate with `dim` residual rows: inlier_threshold when set,
  // else the chi2 quantile of dim at inlier_probability.
  double threshold(int dim) const;
};

// The closed-form weight of a candidate with squared whitened residual s at
// mu (docs/ROBUST_RULES.md, "The method"), and the first mu. initialMu returns a value <= 0 when no
// residual exceeds c2 (every candidate is an inlier: nothing to anneal).
double gncWeight(GncOptions::Loss loss, double s, double mu, double c2);
double gncInitialMu(GncOptions::Loss loss, double s_max, double c2);
double gncNextMu(GncOptions::Loss loss, double mu, double mu_step);

// The change of the total cost (chi2 units) when the weights of some
// factors change by d (per residual row) from those a back-end holds at its
// optimum, to first order: r^T D (I + G D)^-1 r, with r their whitened
// residuals and G = J H^-1 J^T (FactorWeights::residualCovariance). Only
// the rows whose weight changes enter.
double linearisedCostChange(const Eigen::MatrixXd& g, const Eigen::VectorXd& r,
                            const Eigen::VectorXd& d);

// Least-squares solves that polish an alternative's GNC estimate.
inline constexpr int kPolishSolves = 2;

// The doubt rule's alternative (answer_doubt.h), as GNC and
// TruncatedObjectiveCheck solve it: GNC-TLS (`options`, doubt off) over
// `problem`, then kPolishSolves least-squares solves over `inliers` and the
// `candidates` within their `c2` at the estimate before. The estimate, with
// `fits` (one per candidate: 1 within c2 at the last polish, else 0);
// nullopt on a numerical failure. Throws hamal::Error as the solves do.
std::optional<Values> polishedGncSolve(const std::function<std::unique_ptr<Backend>()>& make,
                                       const std::function<bool(const Factor&)>& is_candidate,
                                       GncOptions options, const Step& problem,
                                       const std::vector<FactorPtr>& inliers,
                                       const std::vector<FactorPtr>& candidates,
                                       const std::vector<double>& c2, std::vector<double>* fits);

// The chi2 quantile of `dof` degrees of freedom at probability p in (0, 1).
double chiSquareQuantile(int dof, double p);

class GraduatedNonConvexity : public Backend, public ClosingVerdict {
 public:
  using Predicate = std::function<bool(const Factor&)>;
  // `make` makes the inner back-end (again, for RebuiltFactorWeights);
  // `is_candidate` picks the factors that may be outliers.
  GraduatedNonConvexity(std::function<std::unique_ptr<Backend>()> make, Predicate is_candidate,
                        GncOptions options);
  ~GraduatedNonConvexity() override;

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override;

  // Every candidate received, in arrival order, with its weight now.
  struct Decision {
    const Factor* factor;
    double weight;
    double chi2;  // its s at the estimate when it was last checked
  };
  std::vector<Decision> decisions() const;
  // Whether a weight counts as rejected: below 0.5 for TLS (whose weights
  // end at 0 or 1), below the weight GM gives a residual at c2 at mu = 1
  // (1/4) for GM.
  bool rejected(double weight) const;
  double threshold(const Factor& factor) const;  // c2 of the factor
  const GncOptions& options() const { return options_; }
  // Outer iterations of the last update and of all updates.
  long lastIterations() const { return last_iterations_; }
  long totalIterations() const { return total_iterations_; }
  // Alternatives checked (the closing check's included) and adopted
  // (gnc_doubt=adopt) over all updates.
  long alternativesChecked() const;
  long alternativesAdopted() const { return alternatives_adopted_; }
  // The inner back-end when it offers FactorWeights itself (its estimate
  // and covariance are the ones GNC holds), else null: what PCM's estimate
  // test reads through GNC. The back-ends `make` builds for other purposes
  // (the doubt rule's alternative) are never it.
  Backend* nativeWeightsBackend() const { return native_weights_ ? inner_.get() : nullptr; }
  // The inner back-end's closing verdict first (AprilSAM's: a full
  // back-substitution), in every doubt mode; then the rule "a cheaper
  // alternative" on the answer as it stands, when
  // closures came since it last ran. With gnc_doubt=adopt and
  // gnc_closing=adopt a cheaper alternative is adopted as at an update, and
  // the adopted answer is ok only if no rule fires on it; else it is
  // reported and the estimate is left as it is (the other rules ran at the
  // last update already).
  Status closingVerdict() override;
  // With consistent_group (and the doubt rules on), closingVerdict judges an
  // answer whose last update was in doubt too: it may find and adopt a
  // better one.
  bool judgesUncertainAnswers() const override {
    return options_.consistent_group && options_.doubt != GncOptions::Doubt::kOff;
  }
  // The cheaper-alternative check PCM and max-mixtures get
  // (truncated_objective_check.h), asked at the end of a run instead of the
  // rule above, with the starts its maker chose (hamal_robust's specs: from
  // the answer over every closure, which the rule above leaves out); when
  // adopting, the decisions its cheaper map makes (a closure within
  // its c2 there is in) are adopted, and the check runs again. Fed every
  // step.
  void setClosingCheck(std::unique_ptr<TruncatedObjectiveCheck> check);
  // The back-end the doubt rule's alternative over the recent rejected
  // closures is solved on (none: that alternative is not tried). It is one
  // batch from a start that may be far from its optimum, so a back-end whose
  // batch is one Gauss-Newton step (AprilSAM's, Alg. 3.1) is given more
  // steps there.
  void setAlternativeMaker(std::function<std::unique_ptr<Backend>()> make);

 private:
  struct Candidate {
    const Factor* factor;
    FactorPtr keep;     // holds the factor alive for decisions()
    double weight = 1;  // 0 while not held
    double chi2 = 0;
    double c2 = 0;
    bool held = true;                      // in the inner back-end
    double checked_chi2 = 0;               // not held: chi2 when last decided
    std::vector<const double*> endpoints;  // the inner estimate's parameters
    std::vector<int> dims;                 // their dimensions
    std::vector<double> seen;              // their values at the last check
    int flips = 0;                         // decision changes between updates
    bool was_rejected = false;             // the decision after the last update
  };
  // The doubt rules on an update that converged (answer_doubt.h): sets
  // result's status to kUncertain naming every rule that fired.
  void judge(UpdateResult* result);
  // The alternative (docs/ROBUST_DOUBT_RULES.md): its truncated objective and the weights
  // (1: fits, 0: not) of every candidate; false when it cannot be made. The
  // cheaper of two: GNC from the answer over the rejected closures, and over
  // those of them that arrived since the check before (recent_from_ on)
  // where that keeps every accepted closure.
  // With consistent_group and `in_doubt` (a rule but the alternative's
  // fires on the decisions), the consistent group too.
  bool alternative(double* objective, std::vector<double>* w, bool in_doubt) const;
  // The truncated objective at the estimate, or at `at`.
  double objective() const { return objective(inner_->estimate()); }
  double objective(const Values& at) const;
  void countFlips();
  // The closures the answer accepts that the decisions `w` (one per
  // candidate, 1 in, 0 out) would reject.
  std::size_t dropsOfAdoption(const std::vector<double>& w) const;
  // closingVerdict with consistent_group: the update's rules once more on
  // every closure (the alternatives, adopted as at an update), then the
  // closing check; every rule that fires is named.
  Status catchUpVerdict();
  // The alternative check (checkAlternative) on the decisions as they
  // stand, when `due` and a closure is rejected; none rejected clears its
  // verdict. False on a numerical failure (result's status set).
  bool checkWhenDue(bool due, bool adopt_cheaper, UpdateResult* result);
  // closingVerdict's own rule: this back-end's alternative.
  Status ownClosingVerdict();
  // The inner back-end's closing verdict, where it offers one.
  Status innerClosingVerdict();
  // Takes the decisions `cheaper` (a map a closing rule found cheaper)
  // makes at the stated c2 and judges the answer again (*doubt); false
  // when the adoption failed (*doubt its status).
  bool adoptClosingMap(const Values& cheaper, Status* doubt);
  bool noiseScaleAdopts() const {
    return options_.doubt == GncOptions::Doubt::kAdopt &&
           options_.noise_scale == GncOptions::Doubt::kAdopt;
  }
  bool closingAdopts() const {
    return options_.doubt == GncOptions::Doubt::kAdopt &&
           options_.closing == GncOptions::Doubt::kAdopt;
  }
  // The rule "a cheaper alternative" on the answer as it stands (sets
  // alternative_status_); with `adopt` a cheaper one is adopted and checked
  // once more. False when adopting failed numerically (result's
  // status says so).
  bool checkAlternative(double margin, bool adopt, UpdateResult* result);
  // Adoption: the decisions `w` (1: in, 0: out, one per candidate) of an
  // alternative whose truncated objective is `theirs` (the answer's:
  // `mine`) go into the inner back-end, which is solved again; false on a
  // numerical failure (result's status set).
  bool adopt(const std::vector<double>& w, double mine, double theirs, UpdateResult* result);
  // `alternative` with the rules "flips" and "most rejected" on the
  // decisions as they stand: ok, or kUncertain naming each that fired.
  // `fresh`: the share rule's evidence is remade now (an adopted answer).
  Status decisionDoubt(const Status& alternative, bool fresh = false);
  // The rule "most rejected" with the map's refutation of the rejected
  // closures (near_misses.h), remade where the rule would fire and the
  // candidates grew by kRecheckGrowth since it was last made (or `fresh`);
  // between, the last estimate stands.
  Status shareDoubt(std::size_t rejected_count, bool fresh);
  static constexpr double kRecheckGrowth = 1.25;
  // Anneals `set` (indices into candidates_), all at weight 1 in the inner
  // back-end already solved; adds to `result`.
  void anneal(const std::vector<std::size_t>& set, UpdateResult* result);
  // One set: on the factorisation where it can, else by weighted solves.
  void annealBlock(const std::vector<std::size_t>& set, UpdateResult* result);
  // The mu schedule on the factorisation (docs/ROBUST_RULES.md); false when it cannot
  // run or its weights do not hold at the nonlinear residuals.
  bool annealLinear(std::vector<std::size_t> set, UpdateResult* result);
  // `set` with the tentative closures (accepted where the map could bend to
  // fit almost any measurement) that a new candidate would rather replace:
  // letting one go and taking the new one in lowers the linearised TLS cost
  // below the new candidate's best alone. So a later closure can take an
  // earlier one's place. `g_set` gets G of the returned set where it was
  // computed on the way (else it is left empty).
  std::vector<std::size_t> withTentative(std::vector<std::size_t> set, Eigen::MatrixXd* g_set);
  // Which of `set` are tentative after the decision `w` (before commit).
  void markTentative(const std::vector<std::size_t>& set, const std::vector<double>& w,
                     const Eigen::MatrixXd& g, const std::vector<int>& offset);
  // Appends the set's factors and their row offsets to a stacked residual;
  // returns its length.
  int stack(const std::vector<std::size_t>& set, std::vector<const Factor*>* factors,
            std::vector<int>* offset) const;
  // TLS on the model: the binary weights of `set` that minimise
  // `objective` (the linearised TLS cost of a weight choice), exactly up to
  // kExactLimit candidates, else GNC's schedule and single flips; returns
  // the outer iterations spent.
  // The model: residuals of the set at weights x (to first order).
  using MoveTo = std::function<bool(const std::vector<double>& x, Eigen::VectorXd* residuals)>;
  long decideTruncated(const std::vector<std::size_t>& set, const std::vector<int>& offset,
                       const MoveTo& moveTo,
                       const std::function<double(const std::vector<double>&)>& objective,
                       const std::vector<bool>& locked, std::vector<double>* w);
  // GNC's mu schedule on the model `moveTo` (weights -> residuals) from the
  // least-squares start; the outer iterations, or -1 when it fails or does
  // not converge.
  long annealOnModel(const std::vector<std::size_t>& set, const std::vector<int>& offset,
                     const MoveTo& moveTo, std::vector<double>* w);
  static constexpr std::size_t kExactLimit = 8;
  static constexpr int kLinearRounds = 3;
  static constexpr int kSettleSolves = 2;
  static constexpr double kRevisitMargin = 4;
  static constexpr std::size_t kBlock = 6;  // leaves room for two tentative closures
  static constexpr std::size_t kTentativePool = 8;
  static constexpr double kTentativeVariance = 100;
  // One weighted solve per outer iteration.
  void annealIterative(const std::vector<std::size_t>& set, UpdateResult* result);
  // The first mu for `chi2` of the set's candidates (GTSAM's rule over each
  // candidate's c2); not finite or <= 0 when nothing needs annealing.
  double initialMu(const std::vector<std::size_t>& set, const std::vector<double>& chi2) const;
  bool converged(double mu, bool binary, double cost, double prev_cost) const;
  void notConverged(std::size_t candidates, long iterations, UpdateResult* result) const;
  // Re-evaluates candidate i's chi2 at the inner estimate, records the
  // endpoint values; false when it does not evaluate.
  bool evaluate(std::size_t i);
  void setWeight(std::size_t i, double w);
  // One inner update of `step` (empty by default), merged into `result`;
  // false when it failed numerically (result's status set).
  bool solve(UpdateResult* result, const Step& step = Step());
  // The set's final weights into the back-end: held candidates reweighted,
  // the others added where their weight is not 0; false on a numerical
  // failure.
  bool commit(const std::vector<std::size_t>& set, const std::vector<double>& w,
              UpdateResult* result);
  bool evaluateAll(const std::vector<std::size_t>& set, UpdateResult* result);
  // Old candidates whose weight no longer fits their residual.
  std::vector<std::size_t> revisit(std::size_t first_new);

  std::function<std::unique_ptr<Backend>()> make_;
  std::function<std::unique_ptr<Backend>()> make_alternative_;  // null: make_
  Predicate is_candidate_;
  GncOptions options_;
  std::unique_ptr<Backend> inner_;
  bool native_weights_ = false;  // inner_ offers FactorWeights itself
  FactorWeights* weights_ = nullptr;
  std::vector<Candidate> candidates_;
  std::optional<Refutation> refuted_;   // shareDoubt's evidence
  std::size_t refuted_at_ = 0;          // the candidates when it was made
  std::vector<std::size_t> tentative_;  // indices, oldest first
  std::size_t steps_ = 0;
  long last_iterations_ = 0, total_iterations_ = 0;
  std::vector<FactorPtr> inliers_;  // every factor that is not a candidate
  std::vector<Key> fixed_;
  std::size_t checked_candidates_ = 0;  // candidates at the last alternative check
  std::size_t recent_from_ = 0;         // candidates at the check before it
  Status alternative_status_;           // its verdict, standing until the next
  long alternatives_checked_ = 0, alternatives_adopted_ = 0;
  std::unique_ptr<TruncatedObjectiveCheck> closing_check_;  // null: none
};

}  // namespace hamal::robust
