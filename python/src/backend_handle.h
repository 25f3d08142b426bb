// BackendHandle: a back-end as Python holds it, with the spec and options
// it was made from, and the UpdateResult with the update's wall time, so a
// Python loop reports what hamal_bench's rows report (apps/bench).
#pragma once

#include <map>
#include <memory>
#include <string>

#include "core/backend.h"

namespace hamal::python {

struct TimedUpdateResult : UpdateResult {
  double seconds = 0;  // wall time of Backend::update alone
};

struct BackendHandle {
  std::unique_ptr<Backend> backend;
  std::string spec;
  std::map<std::string, std::string> options;

  TimedUpdateResult update(const Step& step);
};

}  // namespace hamal::python
