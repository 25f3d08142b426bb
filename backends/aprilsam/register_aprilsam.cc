// Registration of AprilSAM and its thesis variants (sec. 3.5.1); see
// register_aprilsam.h.
#include "backends/aprilsam/register_aprilsam.h"

#include "backends/aprilsam/aprilsam_backend.h"

namespace hamal {

void registerAprilSamBackends(Registry& registry) {
  BackendInfo info;
  info.name = "aprilsam";
  info.description =
      "AprilSAM (thesis ch. 3): incremental Cholesky on the affected rows (eq. 3.14, 3.19), "
      "partial back-substitution, adaptive batch updates (Alg. 3.1) with min-heap ordering";
  info.options = aprilsam::AprilSamOptions::optionSpecs();
  info.create = [](const Options& o) -> std::unique_ptr<Backend> {
    return std::make_unique<AprilSamBackend>(aprilsam::AprilSamOptions::fromOptions(o));
  };
  registry.addBackend(info.variant("aprilsam-fullsolve",
                                   "AprilSAM-FullSolve: full back-substitution every step",
                                   {{"backsolve", "full"}}));
  registry.addBackend(info.variant(
      "aprilsam-periodic",
      "AprilSAM-Periodic: a batch every `period` steps (10; the thesis' comparison used 50 "
      "for M3500 and 100 for W10000: aprilsam-periodic:period=50)",
      {{"mode", "periodic"}}));
  registry.addBackend(info.variant(
      "aprilsam-nopredictive",
      "AprilSAM-NoPredictiveOrder: periodic batches, newest node last and BHAMD on the rest",
      {{"mode", "periodic"}, {"ordering", "bhamd"}}));
  registry.addBackend(info.variant(
      "aprilsam-top",
      "AprilSAM whose batch decisions re-eliminate only the affected top of the factor, as "
      "iSAM2 does (reeliminate=top), with NL_T = 10, n_lc = 2 and delta_T = 0.13: not the "
      "thesis' algorithm, hamal's fastest at 1e-4 of the optimum (backends/aprilsam/README.md)",
      {{"reeliminate", "top"}, {"nl_t", "10"}, {"n_lc", "2"}, {"delta_t", "0.13"}}));
  registry.addBackend(std::move(info));
}

}  // namespace hamal
