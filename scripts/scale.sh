#!/usr/bin/env bash
# The scale study: synthetic Manhattan worlds of 10^3 to 10^6 poses
# (apps/sweep/specs/scale.json) through hamal_bench; AprilSAM under the thesis
# protocol at every size, cholesky (sqrt-SAM-Chol) incrementally up to 3000
# poses and as one batch solve (hamal_bench --batch) at every size. Writes
# RESULTS/report/report.md with the log-log plot of cumulative time, per-step
# p99 and peak memory against the number of poses, and prints the fitted
# slopes.
#
#   scripts/scale.sh [RESULTS] [--only GROUP] ...   default RESULTS: results/scale
#
# The 10^6-pose incremental AprilSAM run is long (hours on 2 cores); the sweep
# resumes: finished runs are kept, so it can be stopped and started again.
# Extra arguments go to hamal_sweep.py (e.g. --dry_run). Environment as
# scripts/report.sh (HAMAL_BUILD, JOBS).
set -euo pipefail
cd "$(dirname "$0")/.."
RESULTS="${1:-results/scale}"
shift || true
. scripts/bench_environment.sh

# Sizes one at a time would idle a core; the 10^6 runs need ~10 GB each, so
# at most two at once.
"$PY" apps/sweep/hamal_sweep.py apps/sweep/specs/scale.json --results "$RESULTS" \
  --bench "$BENCH" --jobs "${JOBS:-2}" "$@"
"$PY" apps/report/hamal_report.py "$RESULTS" --title "hamal: scale study"
