// Backend: see backend.h.
#include "core/backend.h"

namespace hamal {

const char* toString(UpdateKind kind) {
  switch (kind) {
    case UpdateKind::kIncremental:
      return "incremental";
    case UpdateKind::kBatch:
      return "batch";
    default:
      return "none";
  }
}

const char* toString(Status::Code code) {
  switch (code) {
    case Status::kOk:
      return "ok";
    case Status::kNumericalFailure:
      return "numerical_failure";
    case Status::kNotConverged:
      return "not_converged";
  }
  return "unknown";
}

Status Status::numericalFailure(std::string message, std::vector<Key> keys) {
  Status s;
  s.code = kNumericalFailure;
  s.message = std::move(message);
  s.keys = std::move(keys);
  return s;
}

}  // namespace hamal
