#!/usr/bin/env bash
# The thesis' evaluation regenerated (sec. 3.5, figs. 3.8 / 3.9, and the nnz
# comparison of fig. 3.3): builds hamal (scripts/setup.sh), installs Debian's
# python3-matplotlib when it is missing, runs the sweep of
# apps/sweep/specs/thesis.json on M3500.toro and city10000.g2o (every
# back-end, the delta_T and period sweeps of fig. 3.8d) into a results folder,
# and writes the report (Markdown + PNG/SVG figures) into RESULTS/report.
#
#   scripts/report.sh [RESULTS] [ARGS]  default RESULTS: results/thesis
#
# ARGS go to hamal_sweep.py, e.g. --executor slurm --partition P --time T to
# run the sweep as a Slurm array job (docs/EXPERIMENTS.md); the report is
# drawn here when the jobs are in.
# Runs already in RESULTS are not run again: a second call only redraws the
# report (seconds), and a sweep killed half-way resumes where it stopped.
# Environment: HAMAL_BUILD=DIR uses the executables in DIR/apps instead of
# building ./build; HAMAL_DATA_DIR=DIR reads the datasets from DIR (default
# ../shared/data); JOBS=N runs N benches at once (default: the cores);
# SPEC=FILE another sweep (SPEC=plugins/gtsam/frontier.json with
# HAMAL_BUILD=<a build with the GTSAM plugin>: AprilSAM's frontier against
# iSAM2's, plugins/gtsam/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
RESULTS="${1:-results/thesis}"
shift || true
SPEC="${SPEC:-apps/sweep/specs/thesis.json}"
. scripts/bench_environment.sh

if ! "$PY" -c "import matplotlib" >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "report: installing python3-matplotlib"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    python3 python3-matplotlib
  PY=/usr/bin/python3
fi

"$PY" apps/sweep/hamal_sweep.py "$SPEC" --results "$RESULTS" --bench "$BENCH" \
  --jobs "${JOBS:-$(nproc)}" "$@"
"$PY" apps/report/hamal_report.py "$RESULTS"
