// LineTokens: see line_tokens.h.
#include "core/line_tokens.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "core/key.h"

namespace hamal {

namespace {

bool printable(unsigned char c) { return c >= 0x20 && c < 0x7f; }

std::string escaped(const std::string& text) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned char c : text) {
    if (printable(c)) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace

std::string quoted(const std::string& text, std::size_t max_chars) {
  if (text.size() <= max_chars) return "'" + escaped(text) + "'";
  return "'" + escaped(text.substr(0, max_chars)) + "...' (" + std::to_string(text.size()) +
         " bytes)";
}

LineTokens::LineTokens(std::string file, int line, std::vector<std::string> tokens)
    : file_(std::move(file)), line_(line), tokens_(std::move(tokens)) {
  if (tokens_.empty()) tokens_.emplace_back();
}

LineTokens LineTokens::split(const std::string& file, int line, const std::string& text) {
  std::istringstream is(text);
  std::vector<std::string> tokens;
  for (std::string t; is >> t;) tokens.push_back(t);
  return LineTokens(file, line, std::move(tokens));
}

std::string LineTokens::where() const { return file_ + ":" + std::to_string(line_); }

// Whatever a reason quotes, the message holds no raw control bytes.
void LineTokens::fail(const std::string& reason) const {
  throw Error(escaped(where() + ": " + reason));
}

const std::string& LineTokens::next(const char* what) {
  if (pos_ >= tokens_.size())
    fail(tag() + " line is truncated: it has " + std::to_string(tokens_.size() - 1) + " fields, " +
         what + " is missing");
  return tokens_[pos_++];
}

double LineTokens::number(const char* what) {
  const std::string& s = next(what);
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  // The whole field, not a prefix: a NUL byte inside it ends strtod early.
  if (end == begin || end != begin + s.size())
    fail(std::string(what) + " is " + quoted(s) + ", not a number (field " +
         std::to_string(pos_ - 1) + " of " + quoted(tag()) + ")");
  if (std::isnan(v) || (std::isinf(v) && errno != ERANGE))
    fail(std::string(what) + " is " + quoted(s) + ": NaN and infinity are not accepted");
  if (!(std::fabs(v) <= kMaxMagnitude))
    fail(std::string(what) + " is " + quoted(s) +
         ": out of range (its magnitude must be at most 1.3e154, whose square a double holds)");
  return v;
}

double LineTokens::angle(const char* what) {
  const double v = number(what);
  if (!(std::fabs(v) <= kMaxAngle))
    fail(std::string(what) + " is " + quoted(tokens_[pos_ - 1]) +
         ": an angle beyond 1e6 rad cannot be wrapped to (-pi, pi] meaningfully");
  return v;
}

std::uint64_t LineTokens::id(const char* what) {
  const std::string& s = next(what);
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(begin, &end, 10);
  if (end == begin || end != begin + s.size() || s[0] == '-' || s[0] == '+' || errno == ERANGE)
    fail(std::string(what) + " is " + quoted(s) + ", not a non-negative integer id" +
         (errno == ERANGE ? " (out of range)" : ""));
  return v;
}

std::uint64_t LineTokens::keyIndex(const char* what) {
  const std::uint64_t v = id(what);
  if (v > Key::kMaxIndex)
    fail(std::string(what) + " " + std::to_string(v) + " is larger than the largest id " +
         std::to_string(Key::kMaxIndex));
  return v;
}

std::string LineTokens::word(const char* what) { return next(what); }

void LineTokens::setRegistry(const Registry* registry, std::string format) {
  registry_ = registry;
  format_ = std::move(format);
}

LineTokens LineTokens::rest(const char* what) {
  next(what);  // fails when nothing is left
  LineTokens inner(file_, line_,
                   {tokens_.begin() + static_cast<std::ptrdiff_t>(pos_ - 1), tokens_.end()});
  inner.setRegistry(registry_, format_);
  pos_ = tokens_.size();
  return inner;
}

void LineTokens::expectEnd() const {
  if (pos_ < tokens_.size())
    fail(tag() + " line has " + std::to_string(tokens_.size() - 1) + " fields, expected " +
         std::to_string(pos_ - 1) + " (extra: " + quoted(tokens_[pos_]) + ")");
}

}  // namespace hamal
