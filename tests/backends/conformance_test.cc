// The built-in batch back-ends through the conformance suite every plugin
// author runs (conformance/backend_conformance.h): cholesky, which defines
// the suite's optimum, and ceres at tolerances tight enough to reach it.
#include "conformance/backend_conformance.h"

HAMAL_BACKEND_CONFORMANCE(Builtin, hamal::testing::registered("cholesky:rel_tolerance=1e-14"),
                          hamal::testing::registered(
                              "ceres:function_tolerance=1e-14,parameter_tolerance=1e-12"));
