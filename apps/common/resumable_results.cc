// ResumableResults: see resumable_results.h.
#include "apps/common/resumable_results.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/line_tokens.h"
#include "core/output_file.h"

namespace hamal::apps {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma - start));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path + ": read error");
  return text.str();
}

// "name value" lines as name -> value (a line without a blank: value "").
std::map<std::string, std::string> parameters(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const std::size_t blank = line.find(' ');
    out[line.substr(0, blank)] = blank == std::string::npos ? "" : line.substr(blank + 1);
  }
  return out;
}

// A parameter's name as a message shows it: as it is when short and
// printable, else quoted (escaped, cut).
std::string shown(const std::string& name) {
  const bool plain = name.size() <= 40 && std::all_of(name.begin(), name.end(),
                                                      [](char c) { return c > 0x20 && c < 0x7f; });
  return plain ? name : quoted(name);
}

void checkConfig(const std::string& path, const std::string& config) {
  const std::string there = readAll(path);
  if (there == config) return;
  const auto old_params = parameters(there), new_params = parameters(config);
  std::string reason = "its content differs from this run's parameters";
  for (const auto& [name, value] : new_params) {
    const auto found = old_params.find(name);
    if (found == old_params.end()) {
      reason = shown(name) + " is not set there and " + quoted(value) + " now";
      break;
    }
    if (found->second != value) {
      reason =
          shown(name) + " is " + quoted(found->second) + " there and " + quoted(value) + " now";
      break;
    }
  }
  if (reason.rfind("its content", 0) == 0)
    for (const auto& [name, value] : old_params)
      if (!new_params.count(name)) {
        reason = shown(name) + " is " + quoted(value) + " there and not set now";
        break;
      }
  throw Error(path + ": this directory holds a run with other parameters (" + reason +
              "); use another --output");
}

}  // namespace

void ResumableResults::verifyConfig(const std::string& dir, const std::string& config) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw Error(dir + ": cannot create the results folder");
  const std::string config_path = (fs::path(dir) / "config.txt").string();
  const std::string rows_path = (fs::path(dir) / "rows.csv").string();
  if (fs::exists(config_path)) {
    checkConfig(config_path, config);
  } else if (fs::exists(rows_path)) {
    throw Error(rows_path + ": results without " + config_path +
                ", so nothing says which parameters made them; use another --output");
  } else {
    writeOutputFileNow(config_path, [&](std::ostream& out) { out << config; });
  }
}

ResumableResults::ResumableResults(const std::string& dir, const std::string& config,
                                   const std::string& header)
    : columns_(splitFields(header)) {
  verifyConfig(dir, config);
  std::error_code ec;
  rows_path_ = (fs::path(dir) / "rows.csv").string();
  const bool have_rows = fs::exists(rows_path_);

  std::string text = have_rows ? readAll(rows_path_) : "";
  // A row is whole when its line break was written: a kill between the two
  // leaves a torn row, dropped here and run again.
  const std::size_t whole = text.empty() || text.back() == '\n'     ? text.size()
                            : text.rfind('\n') == std::string::npos ? 0
                                                                    : text.rfind('\n') + 1;
  if (whole != text.size()) {
    dropped_torn_row_ = true;
    text.resize(whole);
    fs::resize_file(rows_path_, whole, ec);
    if (ec) throw Error(rows_path_ + ": cannot drop the torn last row: " + ec.message());
  }
  std::istringstream in(text);
  std::string line;
  int number = 0;
  if (std::getline(in, line)) {
    number = 1;
    if (line != header)
      throw Error(rows_path_ + ":1: the header is " + quoted(line, 60) + ", expected " +
                  quoted(header, 60) + ": not a results file of this run");
  }
  while (std::getline(in, line)) {
    ++number;
    ResultRow row{number, splitFields(line)};
    if (row.fields.size() != columns_.size())
      throw Error(rows_path_ + ":" + std::to_string(number) + ": " +
                  std::to_string(row.fields.size()) + " fields, the header has " +
                  std::to_string(columns_.size()) + " (a damaged results file)");
    rows_.push_back(std::move(row));
  }
  out_.open(rows_path_, std::ios::app | std::ios::binary);
  if (!out_) throw Error(rows_path_ + ": cannot open for appending");
  if (text.empty()) {
    out_ << header << '\n' << std::flush;
    if (!out_) throw Error(rows_path_ + ": writing failed");
  }
}

std::uint64_t ResumableResults::integer(const ResultRow& row, std::size_t column) const {
  const std::string& s = row.fields.at(column);
  std::uint64_t v = 0;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || error != std::errc() || end != s.data() + s.size())
    throw Error(rows_path_ + ":" + std::to_string(row.line) + ": " + columns_.at(column) + " is " +
                quoted(s) + ", not a non-negative integer");
  return v;
}

void ResumableResults::append(const std::string& row) {
  // One write of the whole line: a kill tears at most this row.
  const std::string line = row + '\n';
  out_.write(line.data(), static_cast<std::streamsize>(line.size()));
  out_.flush();
  if (!out_) throw Error(rows_path_ + ": writing failed");
}

}  // namespace hamal::apps
