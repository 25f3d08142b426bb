// LineTokens: see line_tokens.h.
#include "core/line_tokens.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/error.h"

namespace hamal {

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

void LineTokens::fail(const std::string& reason) const { throw Error(where() + ": " + reason); }

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
  if (end == begin || *end != '\0')
    fail(std::string(what) + " is '" + s + "', not a number (field " + std::to_string(pos_ - 1) +
         " of " + tag() + ")");
  if (!std::isfinite(v))
    fail(std::string(what) + " is '" + s + "': NaN and infinity are not accepted");
  return v;
}

std::uint64_t LineTokens::id(const char* what) {
  const std::string& s = next(what);
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(begin, &end, 10);
  if (end == begin || *end != '\0' || s[0] == '-' || s[0] == '+' || errno == ERANGE)
    fail(std::string(what) + " is '" + s + "', not a non-negative integer id");
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
         std::to_string(pos_ - 1) + " (extra: '" + tokens_[pos_] + "')");
}

}  // namespace hamal
