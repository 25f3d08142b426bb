// hamal_robust: one cell of the robust pose-graph benchmark (apps/robust/
// README.md). Runs one back-end with one loop-closure model (robust=none |
// cauchy | huber | dcs | maxmix | gnc-tls | gnc-gm, options of the back-end
// spec) over a graph spoiled by hamal_spoil, in batch or under the thesis
// protocol, and grades the estimate against the batch optimum of the clean
// graph (the spoiled one minus its listed false edges): ATE after rigid
// alignment, precision and recall of the rejected edges, true loop closures
// rejected, chi2 over the true edges, time. Its command line is hamal_bench's where they overlap,
// so the sweep runner (apps/sweep/hamal_sweep.py --bench hamal_robust) drives it.
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/bench/bench_runner.h"
#include "apps/bench/bench_writers.h"
#include "apps/common/cli.h"
#include "apps/robust/external_solver.h"
#include "apps/robust/false_edge_list.h"
#include "apps/robust/robust_evaluation.h"
#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/pcm_front_end.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/output_file.h"

DEFINE_string(data, "",
              "spoiled graph (hamal_spoil's output; a clean file with an empty list works too)");
DEFINE_string(format, "auto", "format of --data: auto | g2o | toro | gtsam");
DEFINE_string(false_edges, "",
              "its false-edge list (default: DATA.false, where hamal_spoil writes it)");
DEFINE_string(backend, "",
              "back-end spec with the loop-closure model among its options, e.g. "
              "aprilsam:robust=maxmix or ceres:robust=cauchy,loss_scale=2 (see --list-backends)");
DEFINE_string(reference, "cholesky",
              "back-end whose plain least-squares batch solve of the CLEAN graph is the truth the "
              "ATE is measured against");
DEFINE_bool(batch, false,
            "one batch solve of the whole graph from --init's values, instead of the thesis "
            "protocol's one update per pose");
DEFINE_string(init, "odometry", "initial values of the batch solves: odometry | lago");
DEFINE_uint64(chi2_every, 0,
              "incremental runs: chi2 in the rows every k steps (0: last step only)");
DEFINE_bool(diagnose_accepted, true,
            "also solve the clean graph plus the false edges the run left on (least squares, "
            "--reference, from --init) and report the ATE that accepting them costs at best "
            "(ate_accepted: that optimum vs the clean one) and the run's distance to that "
            "optimum (ate_vs_accepted: the back-end's own error)");
DEFINE_string(rows, "", "write per-step rows here (.csv or .jsonl)");
DEFINE_string(summary, "", "write the graded result here (JSON)");
DEFINE_string(output, "",
              "write the final estimate and the graph's factors (false edges too) to this g2o "
              "file; which closures the model rejected is --weights'");
DEFINE_string(estimate, "",
              "grade this estimate instead of running a back-end: the g2o file (its vertices) "
              "that a solver outside hamal wrote for --data (hamal_risam_native; "
              "apps/robust/external_solver.h); no --backend then");
DEFINE_string(decisions, "",
              "with --estimate: that solver's verdict on each loop closure (factor from to "
              "weight rejected); without it its closures are graded by the max-mixture rule");
DEFINE_string(weights, "",
              "write each loop closure's final decision here (CSV: factor index, poses, false, "
              "the model's weight, chi2 at the estimate, rejected)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "runs one back-end with one loop-closure model over a spoiled graph and grades it.\n\n"
    "  hamal_spoil --data ../shared/data/M3500.toro --outliers 100 --out M3500-100.g2o\n"
    "  hamal_robust --data M3500-100.g2o --backend aprilsam:robust=maxmix --summary s.json\n"
    "  hamal_robust --data M3500-100.g2o --backend cholesky:robust=huber --batch\n"
    "  hamal_robust --data M3500-100.g2o --estimate risam.g2o --decisions risam.decisions\n\n"
    "Graded against the clean graph's batch optimum (--reference, least squares): ATE after a\n"
    "rigid alignment, recall (false edges whose max-mixture null hypothesis is active at the\n"
    "end), true loop closures switched off by the same rule, chi2 over the true edges, and the\n"
    "time of the update calls.";

nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); }

// One row per loop closure: what the model made of it at the end.
std::string weightsCsv(const Graph& spoiled, const FalseEdgeList& list,
                       const ModelDecisions& decisions, const Values& estimate,
                       const RobustOptions& robust) {
  std::set<std::size_t> is_false;
  for (const auto& e : list.edges) is_false.insert(e.factor);
  std::ostringstream os;
  os << std::setprecision(9) << "factor,from,to,false,weight,chi2,rejected\n";
  for (std::size_t i = 0; i < spoiled.factors.size(); ++i) {
    const Factor& f = *spoiled.factors[i];
    if (!isLoopClosure(f)) continue;
    const bool decided = i < decisions.rejected.size() && decisions.rejected[i] >= 0;
    const bool rejected = decided ? decisions.rejected[i] == 1
                                  : nullHypothesisActive(spoiled.factors[i], estimate, robust);
    const double w = i < decisions.weight.size() ? decisions.weight[i] : NAN;
    os << i << "," << f.keys()[0].str() << "," << f.keys()[1].str() << ","
       << (is_false.count(i) ? 1 : 0) << ",";
    if (std::isfinite(w)) os << w;
    os << "," << f.chi2(estimate) << "," << (rejected ? 1 : 0) << "\n";
  }
  return os.str();
}

// The command line's checks, in the order the tool has always made them; the
// cell's one back-end spec ("external" when --estimate grades a solver run
// outside hamal).
std::string cellSpec(const std::vector<std::string>& backend_flags,
                     const std::vector<std::string>& positional) {
  if (!positional.empty()) throw Error("unexpected argument '" + positional[0] + "'");
  if (FLAGS_data.empty()) throw Error("--data is required (a graph written by hamal_spoil)");
  checkOutputPaths({{"rows", FLAGS_rows},
                    {"summary", FLAGS_summary},
                    {"weights", FLAGS_weights},
                    {"output", FLAGS_output}},
                   {{"data", FLAGS_data},
                    {"estimate", FLAGS_estimate},
                    {"decisions", FLAGS_decisions},
                    {FLAGS_false_edges.empty() ? "" : "false_edges",
                     FLAGS_false_edges.empty() ? falseEdgesPath(FLAGS_data) : FLAGS_false_edges}});
  std::vector<std::string> specs;
  for (const auto& b : backend_flags)
    if (!b.empty()) specs.push_back(b);
  // --estimate: a solver outside hamal ran; grade its files, least squares'
  // options for what the grading needs of a model (the max-mixture rule,
  // the TLS objective at the default c2).
  const bool external = !FLAGS_estimate.empty();
  if (!external && !FLAGS_decisions.empty())
    throw Error("--decisions goes with --estimate (the outside solver's estimate)");
  if (external && !specs.empty())
    throw Error("--estimate grades a solver run outside hamal: give no --backend");
  if (external && (FLAGS_batch || !FLAGS_rows.empty()))
    throw Error("--estimate grades a finished run: --batch and --rows are the outside solver's");
  if (!external && specs.size() != 1) throw Error("give exactly one --backend (one cell per run)");
  return external ? "external" : specs[0];
}

// What the cell reads: the spoiled graph, its false-edge list and, with
// --estimate, the outside solver's files.
struct CellInputs {
  Graph spoiled;
  std::string list_path;
  FalseEdgeList list;
  Values external_estimate;
  ModelDecisions external_decisions;
};

CellInputs readCellInputs(const Registry& base, const RobustOptions& robust, bool external) {
  CellInputs in;
  in.spoiled = readGraph(FLAGS_data, base, parseFormat(FLAGS_format));
  in.list_path = FLAGS_false_edges.empty() ? falseEdgesPath(FLAGS_data) : FLAGS_false_edges;
  in.list = readFalseEdges(in.list_path);
  checkFalseEdges(in.list, in.spoiled, in.list_path);
  // An outside solver's files are read before the clean optimum is solved:
  // a bad file is an error at once.
  if (external) {
    in.external_estimate = readGraph(FLAGS_estimate, base, Format::kG2o).initial;
    if (!FLAGS_decisions.empty())
      in.external_decisions = readExternalDecisions(FLAGS_decisions, in.spoiled);
  }
  if (robust.method != RobustMethod::kLeastSquares &&
      std::none_of(in.spoiled.factors.begin(), in.spoiled.factors.end(),
                   [](const FactorPtr& f) { return isLoopClosure(*f); }))
    throw Error(FLAGS_data +
                ": no loop closure (a factor between poses whose ids differ by more "
                "than one): robust=" +
                robustMethodName(robust.method) + " has nothing to decide");
  return in;
}

// The spoiled graph minus its listed false edges.
Graph cleanGraph(const Graph& spoiled, const FalseEdgeList& list) {
  Graph clean;
  clean.source = FLAGS_data + " without its false edges";
  clean.initial = spoiled.initial;
  clean.fixed = spoiled.fixed;
  clean.factors = cleanFactors(spoiled, list.edges);
  return clean;
}

// The truth the run is graded against: --reference's batch optimum of the
// clean graph.
BatchOptimum solveCleanOptimum(const Graph& clean, const Registry& base, Initialization init) {
  const ThesisProtocol clean_protocol(clean);
  std::cerr << "clean optimum (" << FLAGS_reference << ")..." << std::flush;
  const BatchOptimum optimum =
      solveBatchOptimum(clean, clean_protocol, 0, base, FLAGS_reference, init);
  std::cerr << " " << optimum.work.seconds << " s, chi2 " << optimum.chi2 << "\n";
  if (!optimum.status.ok() || !std::isfinite(optimum.chi2))
    throw Error("the clean graph's batch optimum failed (" +
                std::string(toString(optimum.status.code)) + ": " + optimum.status.message +
                "): nothing to grade against");
  return optimum;
}

// What the cell's run produced: its estimate and what it cost.
struct CellRun {
  Values estimate;
  double seconds = 0;
  int iterations = 0;
  std::size_t failed_steps = 0, batches = 0;
  Status status;
  std::vector<StepRow> rows;
  std::unique_ptr<Backend> backend;
};

// Runs the back-end with its loop-closure model over the spoiled graph: one
// batch solve, the thesis protocol, or (--estimate) nothing but taking the
// outside solver's estimate.
CellRun runCell(const Graph& model, const ThesisProtocol& protocol, const Registry& registry,
                const std::string& spec, Initialization init, bool external,
                const Values& external_estimate) {
  CellRun r;
  if (external) {
    r.estimate = external_estimate;
    std::cerr << "grading " << FLAGS_estimate << "...";
  } else if (FLAGS_batch) {
    std::cerr << "batch solve " << spec << "..." << std::flush;
    const BatchOptimum run =
        solveBatchOptimum(model, protocol, 0, registry, spec, init, &r.backend);
    r.estimate = run.estimate;
    r.seconds = run.work.seconds;
    r.iterations = run.work.iterations;
    r.status = run.status;
    r.failed_steps = r.status.ok() ? 0 : 1;
    r.batches = 1;
    r.rows.push_back(batchStepRow(run));
  } else {
    std::cerr << "running " << spec << " under the thesis protocol..." << std::flush;
    r.backend = registry.makeBackend(spec);
    RunOptions options;
    options.chi2_every = FLAGS_chi2_every;
    RunResult run = runThesisProtocol(protocol, *r.backend, spec, options);
    r.estimate = run.estimate;
    const RunOutcome outcome = summarizeRows(run.rows);
    r.seconds = outcome.seconds;
    r.iterations = outcome.iterations;
    r.failed_steps = outcome.non_ok_steps;
    r.batches = outcome.batch_steps;
    r.status = outcome.status;
    if (!r.status.ok())
      r.status.message = "step " + std::to_string(outcome.status_step) + ": " + r.status.message;
    r.rows = std::move(run.rows);
  }
  std::cerr << " " << r.seconds << " s\n";
  return r;
}

// The summary's description of the cell and its run, before the grading.
nlohmann::json describeCell(const CellInputs& in, const std::string& spec,
                            const RobustOptions& robust, const CellRun& run,
                            const ThesisProtocol& protocol, Initialization init, bool external,
                            const BatchOptimum& optimum) {
  nlohmann::json s;
  s["dataset"] = FLAGS_data;
  s["false_edge_list"] = in.list_path;
  s["spoiling"] = in.list.spoiling;
  s["spec"] = spec;
  s["backend"] = BackendSpec::parse(spec).name;
  s["robust"] = {{"model", robustMethodName(robust.method)},
                 {"loss_scale", robust.loss_scale},
                 {"dcs_phi", robust.dcs_phi},
                 {"null_weight", robust.null_weight},
                 {"null_scale", robust.null_scale}};
  const Backend* model_backend = run.backend.get();
  if (const auto* pcm = dynamic_cast<const robust::PcmFrontEnd*>(model_backend)) {
    s["pcm_exact"] = pcm->exact();
    s["pcm_kept_rejected"] = pcm->keptRejected();
    model_backend = &pcm->inner();
  }
  if (const auto* gnc = dynamic_cast<const robust::GraduatedNonConvexity*>(model_backend)) {
    s["robust"]["gnc_probability"] = robust.gnc.inlier_probability;
    s["robust"]["gnc_threshold"] = robust.gnc.inlier_threshold;
    s["robust"]["gnc_mu_step"] = robust.gnc.mu_step;
    s["gnc_iterations"] = gnc->totalIterations();
    s["gnc_alternatives_checked"] = gnc->alternativesChecked();
    s["gnc_alternatives_adopted"] = gnc->alternativesAdopted();
  }
  s["mode"] = external ? "external" : FLAGS_batch ? "batch" : "incremental";
  if (external) {
    s["estimate"] = FLAGS_estimate;
    s["decisions"] = FLAGS_decisions;
  }
  s["init"] = initializationName(init);
  s["reference"] = FLAGS_reference;
  s["factors"] = in.spoiled.factors.size();
  s["steps"] = protocol.size();
  s["status"] = toString(run.status.code);
  s["status_message"] = run.status.message;
  s["failed_steps"] = run.failed_steps;
  s["seconds"] = external ? nlohmann::json() : nlohmann::json(run.seconds);
  s["iterations"] = run.iterations;
  s["batches"] = run.batches;
  s["clean_optimum_chi2"] = number(optimum.chi2);
  s["clean_optimum_seconds"] = optimum.work.seconds;
  s["false_edges"] = in.list.edges.size();
  return s;
}

// Where the same data with exactly the accepted false edges lands: the rest
// of the run's ATE is the back-end's, not the edges'.
void diagnoseAcceptedEdges(nlohmann::json& s, const RobustEvaluation& ev, const Graph& clean,
                           const Graph& spoiled, const Values& estimate,
                           const BatchOptimum& optimum, const Registry& base, Initialization init) {
  double ate_accepted = 0, ate_vs = ev.ate.translation_rmse;
  if (!ev.false_accepted.empty()) {
    Graph accepted = clean;
    for (std::size_t i : ev.false_accepted) accepted.factors.push_back(spoiled.factors[i]);
    const ThesisProtocol accepted_protocol(accepted);
    const BatchOptimum with =
        solveBatchOptimum(accepted, accepted_protocol, 0, base, FLAGS_reference, init);
    if (with.status.ok()) {
      ate_accepted =
          absoluteTrajectoryError(with.estimate, optimum.estimate, true).translation_rmse;
      ate_vs = absoluteTrajectoryError(estimate, with.estimate, true).translation_rmse;
    } else {
      ate_accepted = ate_vs = std::numeric_limits<double>::quiet_NaN();
    }
  }
  s["ate_accepted"] = number(ate_accepted);
  s["ate_vs_accepted"] = number(ate_vs);
  std::cout << ", " << ev.false_accepted.size() << " false edge(s) accepted: ATE " << ate_accepted
            << " m for the clean optimum with them, the run " << ate_vs << " m from that optimum";
}

// Grades the run against the clean optimum into the summary and the line on
// stdout; returns the --weights CSV (written after the grading: a write error
// is the tool's, not a grade).
std::string gradeCell(nlohmann::json& s, const CellInputs& in, const CellRun& run,
                      const Graph& clean, const BatchOptimum& optimum, const RobustOptions& robust,
                      const Registry& base, Initialization init, bool external) {
  const Graph& spoiled = in.spoiled;
  const FalseEdgeList& list = in.list;
  const Values& estimate = run.estimate;
  std::string weights;
  try {
    const ModelDecisions decisions =
        external ? in.external_decisions : modelDecisions(spoiled, *run.backend, estimate, robust);
    const RobustEvaluation ev =
        evaluateRobust(spoiled, list.edges, estimate, optimum.estimate, robust, &decisions);
    if (!FLAGS_weights.empty()) weights = weightsCsv(spoiled, list, decisions, estimate, robust);
    s["true_loop_closures"] = ev.true_loop_closures;
    s["ate_translation"] = number(ev.ate.translation_rmse);
    s["ate_rotation"] = number(ev.ate.rotation_rmse);
    s["false_switched_off"] = ev.false_switched_off;
    s["true_switched_off"] = ev.true_switched_off;
    s["recall"] = number(ev.recall());
    s["precision"] = number(ev.precision());
    s["true_switched_off_share"] = number(ev.trueSwitchedOff());
    s["chi2_true"] = number(ev.chi2_true);
    s["tls_objective"] = number(ev.tls_objective);
    s["tls_objective_clean"] = number(ev.tls_objective_clean);
    s["evaluation_error"] = "";
    s["false_accepted"] = ev.false_accepted.size();
    std::cout << ", ATE " << ev.ate.translation_rmse << " m / " << ev.ate.rotation_rmse
              << " rad, recall " << ev.recall() << ", true switched off " << ev.trueSwitchedOff()
              << ", chi2 true " << ev.chi2_true << " (clean optimum " << optimum.chi2 << ")"
              << ", TLS objective " << ev.tls_objective << " (clean optimum "
              << ev.tls_objective_clean << ")";
    if (FLAGS_diagnose_accepted)
      diagnoseAcceptedEdges(s, ev, clean, spoiled, estimate, optimum, base, init);
    std::cout << "\n";
  } catch (const Error& e) {
    // A diverged run is a result of the benchmark, not a failure of the tool.
    for (const char* k :
         {"ate_translation", "ate_rotation", "recall", "precision", "true_switched_off_share",
          "chi2_true", "tls_objective", "tls_objective_clean", "false_accepted", "ate_accepted",
          "ate_vs_accepted"})
      s[k] = nullptr;
    s["evaluation_error"] = e.what();
    std::cout << ", not graded: " << e.what() << "\n";
  }
  return weights;
}

int robust(const std::vector<std::string>& plugins, const std::vector<std::string>& backend_flags,
           const std::vector<std::string>& positional) {
  Registry base;
  setUpRegistry(base, plugins);
  const Registry registry = robustRegistry(base);
  if (printListings(registry)) return 0;
  const std::string spec = cellSpec(backend_flags, positional);
  const bool external = !FLAGS_estimate.empty();
  const RobustOptions robust =
      external ? RobustOptions{}
               : robustOptionsFrom(registry.resolveOptions(BackendSpec::parse(spec)));
  if (FLAGS_reference.empty() || FLAGS_reference == "none")
    throw Error("--reference is needed: the ATE is measured against its clean optimum");
  base.resolveOptions(BackendSpec::parse(FLAGS_reference));
  const Initialization init = parseInitialization(FLAGS_init);

  const CellInputs in = readCellInputs(base, robust, external);
  const Graph clean = cleanGraph(in.spoiled, in.list);
  const BatchOptimum optimum = solveCleanOptimum(clean, base, init);

  Graph model = in.spoiled;
  model.factors = applyRobustMethod(in.spoiled.factors, robust);
  const ThesisProtocol protocol(model);
  const CellRun run =
      runCell(model, protocol, registry, spec, init, external, in.external_estimate);

  nlohmann::json s = describeCell(in, spec, robust, run, protocol, init, external, optimum);
  std::cout << std::setprecision(6) << "hamal_robust: " << spec << (FLAGS_batch ? " batch" : "")
            << " on " << FLAGS_data << " (" << in.list.edges.size() << " false edges): ";
  if (external)
    std::cout << FLAGS_estimate;
  else
    std::cout << run.seconds << " s, " << toString(run.status.code);
  const std::string weights = gradeCell(s, in, run, clean, optimum, robust, base, init, external);
  if (!weights.empty()) writeOutputFile(FLAGS_weights, [&](std::ostream& out) { out << weights; });
  if (!FLAGS_output.empty() && !run.estimate.empty())
    writeG2o(FLAGS_output, run.estimate, in.spoiled.factors, in.spoiled.fixed);
  if (!FLAGS_rows.empty()) writeRowsFile(FLAGS_rows, run.rows);
  if (!FLAGS_summary.empty())
    writeOutputFile(FLAGS_summary, [&](std::ostream& out) { out << s.dump(1) << "\n"; });
  return 0;
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_robust", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto backends = hamal::apps::repeatedFlag(argc, argv, "backend");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::robust(plugins, backends, positional);
  });
}
