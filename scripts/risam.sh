#!/usr/bin/env bash
# riSAM beside hamal's robust models on the same spoiled pose graphs
# (plugins/risam/README.md): spoils the judging graphs, runs aprilsam gnc,
# aprilsam-top gnc, aprilsam maxmix, aprilsam pcm+gnc and riSAM (and
# Kimera-RPGO, when the build has RPGO_SOURCE_DIR) on every file in one
# invocation, grades all with hamal_robust, and writes
# RESULTS/side_by_side.{csv,md}. Resumable; progress on stderr.
#
#   scripts/risam.sh [RESULTS] [risam_side_by_side.py options]
#   scripts/risam.sh results/risam --datasets intel,CSAIL --seeds 1,2,3
#
# RESULTS defaults to results/risam. Environment: RISAM_BUILD=DIR, the build
# configured with RISAM_GTSAM_DIR and RISAM_SOURCE_DIR (default build-risam),
# whose apps/ and plugins/risam/ hold the executables; HAMAL_DATA_DIR=DIR
# reads the datasets from DIR (default ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
RESULTS="results/risam"
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  RESULTS="$1"
  shift
fi
BUILD="${RISAM_BUILD:-build-risam}"
[ -f "$BUILD/CMakeCache.txt" ] || {
  echo "scripts/risam.sh: $BUILD is not configured; plugins/risam/README.md says how" >&2
  exit 1
}
TARGETS=(hamal_spoil hamal_robust hamal_risam_native)
RPGO=()
if grep -q '^RPGO_SOURCE_DIR:PATH=.' "$BUILD/CMakeCache.txt"; then
  TARGETS+=(hamal_rpgo_native)
  RPGO=(--rpgo "$BUILD/plugins/risam/hamal_rpgo_native")
fi
cmake --build "$BUILD" -j2 --target "${TARGETS[@]}"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
exec "$PY" plugins/risam/risam_side_by_side.py "$RESULTS" --bin_dir "$BUILD/apps" \
  --risam "$BUILD/plugins/risam/hamal_risam_native" "${RPGO[@]}" \
  --data_dir "${HAMAL_DATA_DIR:-../shared/data}" "$@"
