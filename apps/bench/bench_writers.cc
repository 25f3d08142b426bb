// Result files of a benchmark: see bench_writers.h.
#include "apps/bench/bench_writers.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/output_file.h"

namespace hamal::apps {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool isJsonName(const std::string& path) {
  return endsWith(path, ".json") || endsWith(path, ".jsonl");
}

std::string number(double v) {
  if (std::isnan(v)) return "";
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

// JSON has no NaN: a figure that could not be computed is null.
nlohmann::json jsonNumber(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

}  // namespace

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

void writeRowsCsv(std::ostream& os, const std::vector<StepRow>& rows, bool header) {
  if (header)
    os << "run,step,backend,kind,reason,status,status_message,seconds,iterations,"
          "columns_recomputed,variables_relinearized,linearize_seconds,order_seconds,"
          "factor_seconds,solve_seconds,other_seconds,chi2,estimate_seconds\n";
  for (const auto& r : rows)
    os << r.run << ',' << r.step << ',' << csvField(r.backend) << ',' << toString(r.kind) << ','
       << csvField(r.reason) << ',' << toString(r.status) << ',' << csvField(r.status_message)
       << ',' << number(r.work.seconds) << ',' << r.work.iterations << ','
       << r.work.columns_recomputed << ',' << r.work.variables_relinearized << ','
       << number(r.work.phases.linearize) << ',' << number(r.work.phases.order) << ','
       << number(r.work.phases.factor) << ',' << number(r.work.phases.solve) << ','
       << number(r.work.phases.other) << ',' << (r.chi2 ? number(*r.chi2) : "") << ','
       << number(r.work.phases.estimate) << '\n';
}

void writeRowsJsonLines(std::ostream& os, const std::vector<StepRow>& rows) {
  for (const auto& r : rows) {
    nlohmann::json j = {{"run", r.run},
                        {"step", r.step},
                        {"backend", r.backend},
                        {"kind", toString(r.kind)},
                        {"reason", r.reason},
                        {"status", toString(r.status)},
                        {"status_message", r.status_message},
                        {"seconds", r.work.seconds},
                        {"iterations", r.work.iterations},
                        {"columns_recomputed", r.work.columns_recomputed},
                        {"variables_relinearized", r.work.variables_relinearized},
                        {"linearize_seconds", r.work.phases.linearize},
                        {"order_seconds", r.work.phases.order},
                        {"factor_seconds", r.work.phases.factor},
                        {"solve_seconds", r.work.phases.solve},
                        {"other_seconds", r.work.phases.other},
                        {"estimate_seconds", r.work.phases.estimate},
                        {"chi2", r.chi2 ? jsonNumber(*r.chi2) : nlohmann::json()}};
    os << j.dump() << '\n';
  }
}

void writeSummaryCsv(std::ostream& os, const std::vector<Summary>& summaries) {
  os << "dataset,backend,steps,repeats,cumulative_seconds,p50_seconds,p90_seconds,p99_seconds,"
        "max_seconds,share_under_10ms,share_under_100ms,batch_steps,non_ok_steps,final_chi2,"
        "optimum_chi2,chi2_ratio,reference,first_failure,update_only_seconds,stopped_by_budget\n";
  for (const auto& s : summaries)
    os << csvField(s.dataset) << ',' << csvField(s.backend) << ',' << s.steps << ',' << s.repeats
       << ',' << number(s.timing.cumulative_seconds) << ',' << number(s.timing.p50) << ','
       << number(s.timing.p90) << ',' << number(s.timing.p99) << ',' << number(s.timing.max) << ','
       << number(s.timing.share_under_10ms) << ',' << number(s.timing.share_under_100ms) << ','
       << s.outcome.batch_steps << ',' << s.outcome.non_ok_steps << ','
       << number(s.accuracy.final_chi2) << ',' << number(s.accuracy.optimum_chi2) << ','
       << number(s.accuracy.chi2_ratio) << ',' << csvField(s.accuracy.reference) << ','
       << csvField(s.outcome.first_failure) << ',' << number(s.timing.update_only_seconds) << ','
       << (s.stopped_by_budget ? 1 : 0) << '\n';
}

void writeSummaryJson(std::ostream& os, const std::vector<Summary>& summaries) {
  nlohmann::json all = nlohmann::json::array();
  for (const auto& s : summaries)
    all.push_back({{"dataset", s.dataset},
                   {"backend", s.backend},
                   {"steps", s.steps},
                   {"repeats", s.repeats},
                   {"cumulative_seconds", jsonNumber(s.timing.cumulative_seconds)},
                   {"update_only_seconds", jsonNumber(s.timing.update_only_seconds)},
                   {"p50_seconds", jsonNumber(s.timing.p50)},
                   {"p90_seconds", jsonNumber(s.timing.p90)},
                   {"p99_seconds", jsonNumber(s.timing.p99)},
                   {"max_seconds", jsonNumber(s.timing.max)},
                   {"share_under_10ms", s.timing.share_under_10ms},
                   {"share_under_100ms", s.timing.share_under_100ms},
                   {"batch_steps", s.outcome.batch_steps},
                   {"non_ok_steps", s.outcome.non_ok_steps},
                   {"final_chi2", jsonNumber(s.accuracy.final_chi2)},
                   {"optimum_chi2", jsonNumber(s.accuracy.optimum_chi2)},
                   {"chi2_ratio", jsonNumber(s.accuracy.chi2_ratio)},
                   {"reference", s.accuracy.reference},
                   {"first_failure", s.outcome.first_failure},
                   {"stopped_by_budget", s.stopped_by_budget}});
  os << all.dump(2) << '\n';
}

void writeRowsFile(const std::string& path, const std::vector<StepRow>& rows) {
  writeOutputFile(path, [&](std::ostream& out) {
    if (isJsonName(path))
      writeRowsJsonLines(out, rows);
    else
      writeRowsCsv(out, rows);
  });
}

void writeSummaryFile(const std::string& path, const std::vector<Summary>& summaries) {
  writeOutputFile(path, [&](std::ostream& out) {
    if (isJsonName(path))
      writeSummaryJson(out, summaries);
    else
      writeSummaryCsv(out, summaries);
  });
}

}  // namespace hamal::apps
