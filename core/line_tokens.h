// LineTokens: one line of a dataset file, split into fields, read field by
// field with errors that name the file, the line and the reason (the
// project's rule for bad input: say where and why, never skip silently).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hamal {

class Registry;

// `text` as a message may quote it: in single quotes, at most `max_chars`
// characters of it ("..." and its length in bytes after a longer one), bytes
// that are not printable ASCII written as \xNN. A 10 MB token or binary
// garbage then still gives a message that fits a terminal.
std::string quoted(const std::string& text, std::size_t max_chars = 40);

class LineTokens {
 public:
  LineTokens(std::string file, int line, std::vector<std::string> tokens);
  // Splits `text` on white space.
  static LineTokens split(const std::string& file, int line, const std::string& text);

  const std::string& tag() const { return tokens_.at(0); }
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  std::size_t size() const { return tokens_.size(); }
  // Fields not yet read (the tag counts as read).
  std::size_t remaining() const { return tokens_.size() - pos_; }

  // Next field as a finite number; `what` names it in the error ("dx").
  double number(const char* what);
  // Next field as an angle in radians: a number of magnitude at most
  // kMaxAngle. Beyond it the spacing of doubles grows so large that wrapping
  // to (-pi, pi] gives an arbitrary angle.
  double angle(const char* what);
  // Next field as a non-negative integer id.
  std::uint64_t id(const char* what);
  // Next field as the index of a variable's Key (key.h): an id, failing when
  // it is larger than Key::kMaxIndex (it would alias another variable).
  std::uint64_t keyIndex(const char* what);
  // Next field as it is.
  std::string word(const char* what);
  // Fails if fields are left over ("12 fields, expected 11").
  void expectEnd() const;

  // The registry and file format the line is read with (the reader sets
  // them), so that a parse function can read an inner factor line through
  // the registry (Registry::parseFactor); nullptr and "" until set.
  void setRegistry(const Registry* registry, std::string format);
  const Registry* registry() const { return registry_; }
  const std::string& format() const { return format_; }
  // The fields not yet read, as a line of their own whose tag is the first of
  // them, with the same file, line, registry and format; this line then
  // counts as read to its end. Fails when no field is left.
  LineTokens rest(const char* what);

  // Throws hamal::Error("file:line: reason").
  [[noreturn]] void fail(const std::string& reason) const;
  std::string where() const;

  // The largest magnitude number() accepts: the square of anything larger
  // overflows a double, so a residual or an information matrix built from
  // it would make chi2 infinite.
  static constexpr double kMaxMagnitude = 1.3e154;
  // The largest magnitude angle() accepts; doubles near it are 1.2e-10 rad apart.
  static constexpr double kMaxAngle = 1e6;

 private:
  const std::string& next(const char* what);

  std::string file_;
  int line_;
  std::vector<std::string> tokens_;
  std::size_t pos_ = 1;
  const Registry* registry_ = nullptr;
  std::string format_;
};

}  // namespace hamal
