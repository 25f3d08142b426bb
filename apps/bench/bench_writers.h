// Result files of a benchmark (docs/PROTOCOL.md, "How to measure"; the
// sweeps and reports of apps/ read them): per-step rows as CSV or JSON lines, and
// summaries as CSV or JSON. The format follows the file name: ".jsonl" or
// ".json" -> JSON, anything else -> CSV. Numbers are written with full
// precision; a chi2 not computed at a step is empty (CSV) or null (JSON).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "apps/bench/bench_runner.h"
#include "apps/bench/bench_summary.h"

namespace hamal::apps {

void writeRowsCsv(std::ostream& os, const std::vector<StepRow>& rows, bool header = true);
void writeRowsJsonLines(std::ostream& os, const std::vector<StepRow>& rows);
void writeSummaryCsv(std::ostream& os, const std::vector<Summary>& summaries);
void writeSummaryJson(std::ostream& os, const std::vector<Summary>& summaries);

// By extension, through OutputFile (whole or not at all; a device or FIFO in
// place); throws hamal::Error when the file cannot be written.
void writeRowsFile(const std::string& path, const std::vector<StepRow>& rows);
void writeSummaryFile(const std::string& path, const std::vector<Summary>& summaries);

// A CSV field, quoted when it holds a comma, a quote or a line break (specs
// such as "ceres:a=1,b=2" do).
std::string csvField(const std::string& text);

}  // namespace hamal::apps
