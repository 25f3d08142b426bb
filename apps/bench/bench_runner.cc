// The benchmark runner: see bench_runner.h.
#include "apps/bench/bench_runner.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/stopwatch.h"
#include "protocol/lago_initialization.h"

namespace hamal::apps {

namespace {

std::size_t stepsToRun(const StepSource& source, std::size_t max_steps) {
  return max_steps ? std::min(max_steps, source.size()) : source.size();
}

// The protocol through a const reference is still a source: its steps depend
// on nothing but the estimate.
class ConstProtocol : public StepSource {
 public:
  explicit ConstProtocol(const ThesisProtocol& protocol) : protocol_(protocol) {}
  std::size_t size() const override { return protocol_.size(); }
  Step step(std::size_t i, const Values& estimate) override { return protocol_.step(i, estimate); }

 private:
  const ThesisProtocol& protocol_;
};

}  // namespace

RunResult runThesisProtocol(const ThesisProtocol& protocol, Backend& backend,
                            const std::string& spec, const RunOptions& options, int run) {
  ConstProtocol source(protocol);
  RunOptions with_prior = options;
  if (protocol.prior()) with_prior.not_scored.push_back(protocol.prior().get());
  return runSteps(source, backend, spec, with_prior, run);
}

ProtocolPrefix protocolPrefix(const ThesisProtocol& protocol, std::size_t steps) {
  ProtocolPrefix out;
  steps = stepsToRun(ConstProtocol(protocol), steps);
  const Factor* prior = protocol.prior().get();
  for (std::size_t i = 0; i < steps; ++i) {
    // The guesses are composed from the previous guesses: odometry only.
    const Step step = protocol.step(i, out.initial);
    for (const auto& [key, entry] : step.new_values) out.initial.insertEntry(key, entry);
    for (const auto& f : step.new_factors)
      if (f.get() != prior) out.factors.push_back(f);
  }
  return out;
}

namespace {
constexpr EnumNames<Initialization, 2> kInitializations = {
    {{Initialization::kOdometry, "odometry"}, {Initialization::kLago, "lago"}}};
}  // namespace

Initialization parseInitialization(const std::string& name) {
  return parseEnum(kInitializations, name, "initialisation");
}

const char* initializationName(Initialization init) { return enumName(kInitializations, init); }

BatchOptimum solveBatchOptimum(const Graph& graph, const ThesisProtocol& protocol,
                               std::size_t steps, const Registry& registry,
                               const std::string& reference_spec, Initialization init,
                               std::unique_ptr<Backend>* solved) {
  BatchOptimum out;
  out.backend = reference_spec;
  out.steps = stepsToRun(ConstProtocol(protocol), steps);
  out.init.from = init;
  std::unique_ptr<Backend> backend = registry.makeBackend(reference_spec);

  Step batch;
  std::vector<FactorPtr> dataset;
  if (out.steps == protocol.size()) {
    batch = protocol.batch();
    for (const auto& f : batch.new_factors)
      if (f.get() != protocol.prior().get()) dataset.push_back(f);
  } else {
    // The optimum of the graph the incremental run saw: the factors of its
    // steps, stepped by a protocol of their own.
    ProtocolPrefix prefix = protocolPrefix(protocol, out.steps);
    Graph sub;
    sub.source = graph.source + " (first " + std::to_string(out.steps) + " steps)";
    sub.factors = prefix.factors;
    for (const auto& [key, entry] : graph.initial)
      if (prefix.initial.contains(key)) sub.initial.insertEntry(key, entry);
    for (Key k : graph.fixed)
      if (prefix.initial.contains(k)) sub.fixed.insert(k);
    ThesisProtocol sub_protocol(sub);
    batch = sub_protocol.batch();
    dataset = prefix.factors;
  }
  if (init == Initialization::kLago) {
    Stopwatch init_watch;
    const Values odometry = batch.new_values;
    LagoResult lago = lagoInitialization(batch.new_factors, batch.new_values);
    out.init.seconds = init_watch.seconds();
    batch.new_values = std::move(lago.values);
    // A fixed variable is held where the file puts it, not where LAGO would.
    for (Key k : batch.fixed) batch.new_values.setEntry(k, odometry.entry(k));
    out.init.report = describe(lago);
  }
  out.init.chi2 = chi2OrNaN(dataset, batch.new_values);
  Stopwatch watch;
  const UpdateResult result = backend->update(batch);
  out.work.seconds = watch.seconds();
  out.work.iterations = result.iterations;
  out.status = result.status;
  out.work.phases = result.time;
  out.work.columns_recomputed = result.columns_recomputed;
  out.work.variables_relinearized = result.variables_relinearized;
  out.estimate = backend->estimate();
  out.chi2 = chi2OrNaN(dataset, out.estimate);
  if (solved) *solved = std::move(backend);
  return out;
}

StepRow batchStepRow(const BatchOptimum& batch) {
  StepRow row;
  row.step = batch.steps ? batch.steps - 1 : 0;
  row.backend = batch.backend;
  row.kind = UpdateKind::kBatch;
  row.reason =
      std::string("one batch solve from ") + initializationName(batch.init.from) + " (--batch)";
  row.status = batch.status.code;
  row.status_message = batch.status.message;
  row.work = batch.work;
  row.chi2 = batch.chi2;
  return row;
}

bool BatchOptimum::usable() const { return status.ok() && std::isfinite(chi2); }

namespace {
std::string outcome(const BatchOptimum& o) {
  if (!o.status.ok()) return std::string(toString(o.status.code)) + ": " + o.status.message;
  return "chi2 " + std::to_string(o.chi2) + " is not finite";
}
}  // namespace

BatchOptimum solveReference(const Graph& graph, const ThesisProtocol& protocol, std::size_t steps,
                            const Registry& registry, const std::string& reference_spec,
                            Initialization init) {
  BatchOptimum first = solveBatchOptimum(graph, protocol, steps, registry, reference_spec, init);
  if (first.usable()) return first;
  const std::string first_why =
      std::string("from ") + initializationName(init) + ": " + outcome(first);
  if (init == Initialization::kLago) {
    first.note = "no optimum: the reference did not converge " + first_why;
    return first;
  }
  // The retry is the reference's own business: LAGO refusing the graph is a
  // note on the missing optimum, not an end to the benchmark.
  BatchOptimum retry;
  try {
    retry =
        solveBatchOptimum(graph, protocol, steps, registry, reference_spec, Initialization::kLago);
  } catch (const Error& e) {
    first.note =
        "no optimum: the reference did not converge " + first_why + "; nor from lago: " + e.what();
    return first;
  }
  if (retry.usable()) {
    retry.note = "retried from lago: the solve " + first_why;
    return retry;
  }
  retry.note = "no optimum: the reference did not converge " + first_why +
               "; nor from lago: " + outcome(retry);
  return retry;
}

}  // namespace hamal::apps
