#!/usr/bin/env bash
# The robust pose-graph benchmark against false loop closures
# (apps/robust/README.md): spoils M3500, intel, city10000, manhattan and CSAIL
# with N = 0, 100, 1000 false loop closures under the four Vertigo policies and
# five seeds, runs every loop-closure model (least squares, Cauchy, DCS,
# max-mixture, GNC with TLS and GM, PCM, PCM + GNC) in batch (cholesky, ceres),
# incremental GNC under the thesis protocol (aprilsam, aprilsam-top) and
# GTSAM's GncOptimizer when its plugin is built, through the house sweep
# runner, and writes one table per dataset, an ATE-vs-N plot per policy and
# the targets' verdicts into RESULTS/report.
#
#   scripts/robust.sh [RESULTS] [hamal_robust_sweep.py options]
#   scripts/robust.sh results/robust --quick     # one dataset, policy and seed
#   scripts/robust.sh results/robust --datasets M3500 --policies random --outliers 0,1000 --seeds 2
#
# RESULTS defaults to results/robust. Runs already there are not run again: a
# second call only redraws the report, and a sweep killed half-way resumes.
# Environment: HAMAL_BUILD=DIR uses DIR/apps's executables instead of building
# ./build; HAMAL_DATA_DIR=DIR reads the datasets from DIR (default
# ../shared/data); JOBS=N runs N at once (default 1, so times are not shared
# between runs); SPEC=FILE another sweep spec.
set -euo pipefail
cd "$(dirname "$0")/.."
RESULTS="results/robust"
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  RESULTS="$1"
  shift
fi
SPEC="${SPEC:-apps/sweep/specs/robust.json}"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3

if [ -n "${HAMAL_BUILD:-}" ]; then
  BIN="$HAMAL_BUILD/apps"
else
  [ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build build -j2 --target hamal_spoil hamal_robust
  BIN=build/apps
fi

# A run that failed or hit the timeout is a result too (the report lists it),
# so the report is drawn whatever the sweep returns, and its status kept.
status=0
"$PY" apps/robust/hamal_robust_sweep.py "$SPEC" --results "$RESULTS" --bin_dir "$BIN" \
  --jobs "${JOBS:-1}" "$@" || status=$?
"$PY" apps/robust/hamal_robust_report.py "$RESULTS"
exit "$status"
