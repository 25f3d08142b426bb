// The GTSAM plugin's entry point (core/plugin.h): GTSAM's iSAM2 and batch
// Levenberg-Marquardt and GncOptimizer as hamal back-ends ("isam2",
// "gtsam-lm", "gtsam-gnc"), for the
// side-by-side comparisons of thesis sec. 3.5 run with one protocol, one
// timer and one chi2 evaluator. Built only where find_package(GTSAM) finds
// GTSAM 4.3 (develop) or newer (README.md here says how to build it beside hamal).
#include "core/plugin.h"
#include "gtsam_gnc_backend.h"
#include "gtsam_lm_backend.h"
#include "isam2_backend.h"

HAMAL_PLUGIN(registry) {
  registry->addBackend(hamal::gtsam_plugin::isam2Info());
  registry->addBackend(hamal::gtsam_plugin::gtsamLmInfo());
  registry->addBackend(hamal::gtsam_plugin::gtsamGncInfo());
}
