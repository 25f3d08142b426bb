// The CARMEN log reader's flags (carmen_log_flags.h): one definition, one
// mapping to CarmenReadOptions, for every tool that reads a log.
#include "apps/carmen/carmen_log_flags.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

DEFINE_double(max_time_reversal, 1.0,
              "CARMEN log: seconds a record may fall behind the latest of its stream (a laser, "
              "or the odometry) before the log is refused");
DEFINE_double(no_return_range, 0,
              "CARMEN log: FLASER/RLASER range at or beyond which a beam is no return, m; 0: the "
              "log's declared maximum (see --declared_max_range), else the largest range many "
              "beams reach less 0.5% (apps/carmen/README.md)");
DEFINE_bool(declared_max_range, true,
            "CARMEN log: take the maximum range the log declares (PARAM robot_front_laser_max, "
            "robot_rear_laser_max) as FLASER/RLASER's no return when --no_return_range is 0");

namespace hamal::carmen {

CarmenReadOptions readOptionsFromFlags() {
  const auto check = [](const char* flag, double value, const char* unit) {
    if (!(value >= 0) || !std::isfinite(value)) {
      std::ostringstream m;
      m << "--" << flag << " " << value << ": must be a number of " << unit << " >= 0";
      throw Error(m.str());
    }
  };
  check("max_time_reversal", FLAGS_max_time_reversal, "seconds");
  check("no_return_range", FLAGS_no_return_range, "metres");
  CarmenReadOptions o;
  o.max_time_reversal = FLAGS_max_time_reversal;
  o.no_return_range = FLAGS_no_return_range;
  o.declared_max_range = FLAGS_declared_max_range;
  o.validate();
  return o;
}

}  // namespace hamal::carmen
