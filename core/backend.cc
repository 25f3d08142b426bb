// Backend: see backend.h.
#include "core/backend.h"

#include "core/enum_names.h"

namespace hamal {

namespace {
constexpr EnumNames<UpdateKind, 3> kUpdateKinds = {{{UpdateKind::kNone, "none"},
                                                    {UpdateKind::kIncremental, "incremental"},
                                                    {UpdateKind::kBatch, "batch"}}};
constexpr EnumNames<Status::Code, 3> kStatusCodes = {
    {{Status::kOk, "ok"},
     {Status::kNumericalFailure, "numerical_failure"},
     {Status::kNotConverged, "not_converged"}}};
}  // namespace

const char* toString(UpdateKind kind) { return enumName(kUpdateKinds, kind); }
const char* toString(Status::Code code) { return enumName(kStatusCodes, code); }

Status Status::numericalFailure(std::string message, std::vector<Key> keys) {
  Status s;
  s.code = kNumericalFailure;
  s.message = std::move(message);
  s.keys = std::move(keys);
  return s;
}

}  // namespace hamal
