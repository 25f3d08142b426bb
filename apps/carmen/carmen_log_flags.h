// The command-line flags of the CARMEN log reader (carmen_log.h), defined
// once for every tool that reads a log (hamal_log, hamal_flag carmen,
// hamal_moss experiment --data), so that each takes them by the same names:
//   --max_time_reversal   CarmenReadOptions::max_time_reversal (s)
//   --no_return_range     CarmenReadOptions::no_return_range (m; 0: declared or inferred)
//   --declared_max_range  CarmenReadOptions::declared_max_range
// A tool links hamal_carmen_flags and calls readOptionsFromFlags().
#pragma once

#include <gflags/gflags.h>

#include "apps/carmen/carmen_log.h"

DECLARE_double(max_time_reversal);
DECLARE_double(no_return_range);
DECLARE_bool(declared_max_range);

namespace hamal::carmen {

// The reader's options from the flags; throws hamal::Error naming the flag
// of a value out of range.
CarmenReadOptions readOptionsFromFlags();

}  // namespace hamal::carmen
