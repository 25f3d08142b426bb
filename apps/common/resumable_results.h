// ResumableResults: the results folder of a runner that an interrupted
// invocation resumes (hamal_moss experiment). The folder holds config.txt,
// the parameters that made it, one "name value" per line, and rows.csv, a
// header and one comma-separated row per finished unit of work. Before a
// run extends a folder it is verified, so that two experiments' rows never
// mix and a damaged file is never taken as results:
//   - a config.txt that differs from this run's is refused, naming the first
//     parameter that differs; rows.csv without config.txt is refused;
//   - every complete row must have the header's number of fields (else
//     "rows.csv:LINE: ..."); a last row cut by a kill (no line break) is
//     dropped from the file, and its unit is run again.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace hamal::apps {

struct ResultRow {
  int line = 0;  // in rows.csv, from 1 (the header)
  std::vector<std::string> fields;
};

class ResumableResults {
 public:
  // Creates `dir` if needed, verifies (or writes) its config.txt against
  // `config` and its rows.csv against `header` (the column names joined by
  // ','), and opens rows.csv for appending. Throws hamal::Error.
  ResumableResults(const std::string& dir, const std::string& config, const std::string& header);

  // The config.txt check alone, for a worker that adds files beside the rows
  // (a MOSS climb run as its own process) and must not touch rows.csv: the
  // same refusals; config.txt is written when the folder is new. Throws
  // hamal::Error.
  static void verifyConfig(const std::string& dir, const std::string& config);

  // The rows already in the folder, in order.
  const std::vector<ResultRow>& rows() const { return rows_; }
  // True when a torn last row was dropped.
  bool droppedTornRow() const { return dropped_torn_row_; }
  // Field `column` of `row` as a non-negative integer; Error
  // "rows.csv:LINE: <column name> is 'x4', not a non-negative integer".
  std::uint64_t integer(const ResultRow& row, std::size_t column) const;
  // Appends one row (the fields joined by ','), whole, flushed; Error when
  // the write fails.
  void append(const std::string& row);
  const std::string& rowsPath() const { return rows_path_; }

 private:
  std::string rows_path_;
  std::vector<std::string> columns_;
  std::vector<ResultRow> rows_;
  bool dropped_torn_row_ = false;
  std::ofstream out_;
};

}  // namespace hamal::apps
