// FullPrecision: writes doubles with 17 significant digits (and the default
// float format) for the span of a writeFields call, so that a factor written
// to a file and read back is the same factor bit for bit whatever precision
// or format the caller's stream had (graph_io.h: "reading the file back gives
// the same graph").
#pragma once

#include <ios>

namespace hamal {

class FullPrecision {
 public:
  explicit FullPrecision(std::ios_base& stream)
      : stream_(stream), precision_(stream.precision(17)), flags_(stream.flags()) {
    stream.unsetf(std::ios_base::floatfield);
  }
  ~FullPrecision() {
    stream_.precision(precision_);
    stream_.flags(flags_);
  }
  FullPrecision(const FullPrecision&) = delete;
  FullPrecision& operator=(const FullPrecision&) = delete;

 private:
  std::ios_base& stream_;
  std::streamsize precision_;
  std::ios_base::fmtflags flags_;
};

}  // namespace hamal
