// Backend: see backend.h.
#include "core/backend.h"

#include "core/enum_names.h"

namespace hamal {

namespace {
constexpr EnumNames<UpdateKind, 3> kUpdateKinds = {{{UpdateKind::kNone, "none"},
                                                    {UpdateKind::kIncremental, "incremental"},
                                                    {UpdateKind::kBatch, "batch"}}};
constexpr EnumNames<Status::Code, 4> kStatusCodes = {
    {{Status::kOk, "ok"},
     {Status::kNumericalFailure, "numerical_failure"},
     {Status::kNotConverged, "not_converged"},
     {Status::kUncertain, "uncertain"}}};
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

Status Status::uncertain(std::string message) {
  Status s;
  s.code = kUncertain;
  s.message = std::move(message);
  return s;
}

}  // namespace hamal
