// The step runner (apps/bench/step_runner.h): its hooks see every step in
// order around the timed update, a run without score computes no chi2, rows
// keep UpdateKind and Status::Code typed, and summarizeRows' rule for a run
// whose steps did not all converge, and the closing verdict asked after
// the last update, before the last chi2.
#include "apps/bench/step_runner.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/closing_verdict.h"
#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"

namespace hamal::apps {
namespace {

// A chain of poses one metre apart, one step each, and a back-end that
// answers each update with a scripted status.
class Chain : public StepSource {
 public:
  explicit Chain(std::size_t n) : n_(n) {}
  std::size_t size() const override { return n_; }
  Step step(std::size_t i, const Values& estimate) override {
    Step s;
    s.index = i;
    if (i == 0) {
      s.new_values.insert(X(0), Pose2());
      s.new_factors.push_back(
          std::make_shared<PriorFactor>(X(0), Pose2(), Eigen::Matrix3d::Identity()));
    } else {
      s.new_values.insert(X(i), estimate.pose(X(i - 1)).compose(Pose2(1, 0, 0)));
      s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i - 1), X(i), Pose2(1, 0, 0),
                                                              Eigen::Matrix3d::Identity()));
    }
    asked.push_back(i);
    return s;
  }
  std::vector<std::size_t> asked;

 private:
  std::size_t n_;
};

class Scripted : public Backend {
 public:
  explicit Scripted(std::vector<Status::Code> codes) : codes_(std::move(codes)) {}
  UpdateResult update(const Step& step) override {
    for (const auto& [key, entry] : step.new_values) values_.insertEntry(key, entry);
    UpdateResult r;
    r.kind = step.index % 2 ? UpdateKind::kIncremental : UpdateKind::kBatch;
    r.status.code = codes_.at(step.index);
    if (!r.status.ok()) r.status.message = "scripted " + std::to_string(step.index);
    r.iterations = 2;
    return r;
  }
  const Values& estimate() const override { return values_; }

 private:
  std::vector<Status::Code> codes_;
  Values values_;
};

TEST(StepRunner, HooksSurroundEachUpdateInOrderAndRowsAreTyped) {
  Chain chain(4);
  Scripted backend({Status::kOk, Status::kOk, Status::kNotConverged, Status::kOk});
  std::vector<std::string> calls;
  RunOptions options;
  options.hooks.before_step = [&](std::size_t i) {
    calls.push_back("before " + std::to_string(i));
    // The step is not made yet: the runner asks the source after this hook.
    EXPECT_EQ(chain.asked.size(), i);
  };
  options.hooks.after_update = [&](std::size_t i, const Step& step, const UpdateResult& r,
                                   const Backend& b) {
    calls.push_back("after " + std::to_string(i));
    EXPECT_EQ(step.index, i);
    EXPECT_TRUE(b.estimate().contains(X(i)));
    EXPECT_EQ(r.status.code, i == 2 ? Status::kNotConverged : Status::kOk);
  };
  const RunResult run = runSteps(chain, backend, "scripted", options);
  EXPECT_EQ(calls, (std::vector<std::string>{"before 0", "after 0", "before 1", "after 1",
                                             "before 2", "after 2", "before 3", "after 3"}));
  ASSERT_EQ(run.rows.size(), 4u);
  EXPECT_EQ(run.rows[0].kind, UpdateKind::kBatch);
  EXPECT_EQ(run.rows[1].kind, UpdateKind::kIncremental);
  EXPECT_EQ(run.rows[2].status, Status::kNotConverged);
  EXPECT_EQ(run.rows[2].status_message, "scripted 2");
  // Scored: the chain's factors are all satisfied at the composed values.
  ASSERT_TRUE(run.rows.back().chi2.has_value());
  EXPECT_EQ(run.final_chi2, 0.0);
  EXPECT_EQ(run.dataset_factors, 4u);
}

TEST(StepRunner, WithoutScoreNoChi2IsComputed) {
  Chain chain(3);
  Scripted backend({Status::kOk, Status::kOk, Status::kOk});
  RunOptions options;
  options.score = false;
  const RunResult run = runSteps(chain, backend, "scripted", options);
  ASSERT_EQ(run.rows.size(), 3u);
  for (const StepRow& row : run.rows) EXPECT_FALSE(row.chi2.has_value());
  EXPECT_EQ(run.dataset_factors, 0u);
  EXPECT_EQ(run.estimate.size(), 3u);
}

// A back-end with a verdict for the end of the run (core/closing_verdict.h).
class WithVerdict : public Scripted, public ClosingVerdict {
 public:
  WithVerdict(std::vector<Status::Code> codes, Status verdict, bool rejudges = false)
      : Scripted(std::move(codes)), verdict_(std::move(verdict)), rejudges_(rejudges) {}
  Status closingVerdict() override {
    ++asked;
    return verdict_;
  }
  bool judgesUncertainAnswers() const override { return rejudges_; }
  int asked = 0;

 private:
  Status verdict_;
  bool rejudges_;
};

// The run's last row carries the closing verdict when the last update
// said ok; the verdict is asked for once, after the last step, and never
// overrides a worse status of the update itself.
TEST(StepRunner, TheClosingVerdictIsTheLastRowsStatus) {
  {
    Chain chain(3);
    WithVerdict backend({Status::kOk, Status::kOk, Status::kOk}, Status::uncertain("late doubt"));
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 1);
    ASSERT_EQ(run.rows.size(), 3u);
    EXPECT_EQ(run.rows[1].status, Status::kOk);
    EXPECT_EQ(run.rows[2].status, Status::kUncertain);
    EXPECT_EQ(run.rows[2].status_message, "late doubt");
    EXPECT_EQ(summarizeRows(run.rows).status.code, Status::kUncertain);
  }
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kNotConverged}, Status::uncertain("late doubt"));
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 0);
    EXPECT_EQ(run.rows.back().status, Status::kNotConverged);
  }
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kOk}, Status());
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 1);
    EXPECT_EQ(run.rows.back().status, Status::kOk);
  }
}

// After an uncertain last update the verdict is asked only of a back-end
// that judges such answers (GNC's gnc_group=on), and then its status,
// ok included, is the row's; a failure is never re-judged.
TEST(StepRunner, AnUncertainAnswerIsRejudgedOnlyByABackendThatSaysSo) {
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kUncertain}, Status());
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 0);
    EXPECT_EQ(run.rows.back().status, Status::kUncertain);
  }
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kUncertain}, Status(), true);
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 1);
    EXPECT_EQ(run.rows.back().status, Status::kOk);
    EXPECT_EQ(run.rows.back().status_message, "");
  }
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kUncertain}, Status::uncertain("still"), true);
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(run.rows.back().status, Status::kUncertain);
    EXPECT_EQ(run.rows.back().status_message, "still");
  }
  {
    Chain chain(2);
    WithVerdict backend({Status::kOk, Status::kNumericalFailure}, Status(), true);
    const RunResult run = runSteps(chain, backend, "verdict", RunOptions());
    EXPECT_EQ(backend.asked, 0);
    EXPECT_EQ(run.rows.back().status, Status::kNumericalFailure);
  }
}

// A back-end whose closing verdict adopts another answer: the last pose
// one metre to the side.
class Adopting : public Backend, public ClosingVerdict {
 public:
  UpdateResult update(const Step& step) override {
    for (const auto& [key, entry] : step.new_values) values_.insertEntry(key, entry);
    last_ = step.new_values.begin()->first;
    return UpdateResult();
  }
  const Values& estimate() const override { return values_; }
  Status closingVerdict() override {
    values_.set(last_, values_.pose(last_).compose(Pose2(0, 1, 0)));
    return Status();
  }

 private:
  Values values_;
  Key last_;
};

// The last chi2 and the run's estimate are read after the closing verdict,
// which may have adopted a better answer (core/closing_verdict.h).
TEST(StepRunner, TheLastChi2AndEstimateAreTheClosingVerdicts) {
  Chain chain(3);
  Adopting backend;
  const RunResult run = runSteps(chain, backend, "adopting", RunOptions());
  ASSERT_TRUE(run.rows.back().chi2.has_value());
  EXPECT_NEAR(*run.rows.back().chi2, 1.0, 1e-12);  // 1 m against an information of 1
  EXPECT_NEAR(run.final_chi2, 1.0, 1e-12);
  EXPECT_NEAR(run.estimate.pose(X(2)).y, 1.0, 1e-12);
}

std::vector<StepRow> rowsOf(const std::vector<Status::Code>& codes) {
  std::vector<StepRow> rows(codes.size());
  for (std::size_t i = 0; i < codes.size(); ++i) {
    rows[i].step = i;
    rows[i].status = codes[i];
    rows[i].status_message = codes[i] == Status::kOk ? "" : "why " + std::to_string(i);
    rows[i].work.seconds = 0.5;
    rows[i].work.iterations = 3;
    rows[i].kind = i == 0 ? UpdateKind::kBatch : UpdateKind::kIncremental;
  }
  return rows;
}

// The rule the tools used to disagree on: an earlier step that did not
// converge does not hide a later numerical failure, every non-ok step
// counts, and only a last step that failed numerically fails the run.
TEST(SummarizeRows, ANumericalFailureOutranksAnEarlierStepThatDidNotConverge) {
  const RunOutcome o =
      summarizeRows(rowsOf({Status::kOk, Status::kNotConverged, Status::kNumericalFailure,
                            Status::kNumericalFailure, Status::kOk}));
  EXPECT_EQ(o.steps, 5u);
  EXPECT_EQ(o.non_ok_steps, 3u);
  EXPECT_EQ(o.batch_steps, 1u);
  EXPECT_DOUBLE_EQ(o.seconds, 2.5);
  EXPECT_EQ(o.iterations, 15);
  EXPECT_EQ(o.status.code, Status::kNumericalFailure);
  EXPECT_EQ(o.status_step, 2u);
  EXPECT_EQ(o.status.message, "why 2");
  EXPECT_EQ(o.describe(), "step 2: numerical_failure: why 2");
  EXPECT_FALSE(o.failed);  // the run went on to an ok last step
}

TEST(SummarizeRows, ALastStepThatDidNotConvergeIsReportedButNotAFailure) {
  const RunOutcome o =
      summarizeRows(rowsOf({Status::kOk, Status::kNotConverged, Status::kNotConverged}));
  EXPECT_EQ(o.status.code, Status::kNotConverged);
  EXPECT_EQ(o.describe(), "step 1: not_converged: why 1");
  EXPECT_EQ(o.non_ok_steps, 2u);
  EXPECT_FALSE(o.failed);
  const RunOutcome f = summarizeRows(rowsOf({Status::kOk, Status::kNumericalFailure}));
  EXPECT_TRUE(f.failed);
  const RunOutcome ok = summarizeRows(rowsOf({Status::kOk, Status::kOk}));
  EXPECT_TRUE(ok.status.ok());
  EXPECT_EQ(ok.describe(), "");
  EXPECT_FALSE(ok.failed);
  EXPECT_FALSE(summarizeRows({}).failed);
}

// An answer in doubt is the last step's: an earlier step's doubt that later
// updates resolved is not the run's, and doubt ranks below the failures.
TEST(SummarizeRows, UncertainCountsOnlyOnTheLastStep) {
  const RunOutcome resolved = summarizeRows(rowsOf({Status::kOk, Status::kUncertain, Status::kOk}));
  EXPECT_TRUE(resolved.status.ok());
  EXPECT_EQ(resolved.non_ok_steps, 0u);
  const RunOutcome last =
      summarizeRows(rowsOf({Status::kUncertain, Status::kOk, Status::kUncertain}));
  EXPECT_EQ(last.status.code, Status::kUncertain);
  EXPECT_EQ(last.describe(), "step 2: uncertain: why 2");
  EXPECT_EQ(last.non_ok_steps, 1u);
  EXPECT_FALSE(last.failed);
  const RunOutcome worse =
      summarizeRows(rowsOf({Status::kOk, Status::kNotConverged, Status::kUncertain}));
  EXPECT_EQ(worse.status.code, Status::kNotConverged);
  EXPECT_EQ(worse.non_ok_steps, 2u);
}

}  // namespace
}  // namespace hamal::apps
