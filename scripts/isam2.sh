#!/usr/bin/env bash
# AprilSAM against GTSAM's iSAM2, side by side (thesis sec. 3.5, tables
# 3.2-3.4 and the scale study): one hamal_bench invocation per dataset runs
# every back-end under the thesis protocol with one timer and one chi2
# evaluator, each --repeat times (medians), on M3500.toro, intel.g2o,
# city10000.g2o and generated Manhattan worlds; then plugins/gtsam/side_by_side.py writes
# RESULTS/side_by_side.{csv,md} and the scale plot RESULTS/scale.{png,svg}
# (cumulative time against poses, fitted slopes).
#
#   GTSAM_DIR=/work/gtsam-install/lib/cmake/GTSAM scripts/isam2.sh [RESULTS]
#
# GTSAM_DIR (GTSAM's CMake package, built as plugins/gtsam/README.md says)
# builds the plugin into ./build; without it an existing
# build/plugins/libhamal_gtsam_plugin.so is used. Environment:
#   HAMAL_BUILD=DIR   the executables and plugin of DIR instead of ./build
#   DATASETS="M3500.toro intel.g2o city10000.g2o"   files in HAMAL_DATA_DIR
#     (set and empty: none)
#   SIZES="1000 10000"   generated worlds (seed 1); add 100000 for 10^5
#     (set and empty: none)
#   BACKENDS="aprilsam;isam2"   every dataset; SMALL_BACKENDS (default
#     "isam2:relinearize_threshold=0.001,relinearize_skip=1") are added on
#     datasets of at most SMALL_POSES poses (default 4000)
#   REPEAT=3   runs per back-end (times are medians)
#   BUDGET=0   seconds of update calls after which a back-end's run stops
#     (hamal_bench --time_budget; 0: none): for the 10^5 world, where iSAM2
#     takes hours, its curve up to the budget against aprilsam's whole run
#   RESIDUAL=measurement   the between residual every back-end minimises
#     (measurement: GTSAM's and g2o's; thesis: the thesis' eq. 2.28-2.31)
# A dataset whose RESULTS/<name>/summary.csv exists is not run again, so an
# interrupted run resumes at the dataset it stopped in; delete that folder
# to redo one.
set -euo pipefail
cd "$(dirname "$0")/.."
RESULTS="${1:-results/isam2}"
DATA_DIR="${HAMAL_DATA_DIR:-../shared/data}"
DATASETS="${DATASETS-M3500.toro intel.g2o city10000.g2o}"
SIZES="${SIZES-1000 10000}"
BACKENDS="${BACKENDS:-aprilsam;isam2}"
SMALL_BACKENDS="${SMALL_BACKENDS-isam2:relinearize_threshold=0.001,relinearize_skip=1}"
SMALL_POSES="${SMALL_POSES:-4000}"
REPEAT="${REPEAT:-3}"
BUDGET="${BUDGET:-0}"
RESIDUAL="${RESIDUAL:-measurement}"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3

if [ -n "${HAMAL_BUILD:-}" ]; then
  BUILD="$HAMAL_BUILD"
else
  BUILD=build
  if [ -n "${GTSAM_DIR:-}" ]; then
    cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache \
      -DHAMAL_WITH_GTSAM=ON -DGTSAM_DIR="$GTSAM_DIR" >/dev/null
  elif [ ! -f "$BUILD/CMakeCache.txt" ]; then
    cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >/dev/null
  fi
  nice cmake --build "$BUILD" -j"$(nproc)" --target hamal_bench hamal_gtsam_plugin
fi
BENCH="$BUILD/apps/hamal_bench"
PLUGIN="$BUILD/plugins/libhamal_gtsam_plugin.so"
if [ ! -f "$PLUGIN" ]; then
  echo "isam2.sh: no $PLUGIN: build GTSAM (plugins/gtsam/README.md) and give GTSAM_DIR" >&2
  exit 1
fi
mkdir -p "$RESULTS"

# run NAME POSES ARGS...: one hamal_bench invocation, into RESULTS/NAME.
run() {
  local name="$1" poses="$2"
  shift 2
  local out="$RESULTS/$name"
  if [ -f "$out/summary.csv" ]; then
    echo "== $name: done already ($out)"
    return
  fi
  local backends="$BACKENDS"
  if [ -n "$SMALL_BACKENDS" ] && [ "$poses" -le "$SMALL_POSES" ]; then
    backends="$backends;$SMALL_BACKENDS"
  fi
  local tmp="$out.partial"
  rm -rf "$tmp"
  mkdir -p "$tmp"
  local cmd=("$BENCH" --plugin "$PLUGIN" "$@" --backend "$backends" --repeat "$REPEAT"
             --residual "$RESIDUAL" --chi2_every 0 --time_budget "$BUDGET" --rows "$tmp/rows.csv"
             --summary "$tmp/summary.csv")
  {
    echo "command: ${cmd[*]}"
    echo "residual: $RESIDUAL"
    echo "repeats: $REPEAT"
    echo "revision: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
    echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
    echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
  } >"$tmp/machine.txt"
  echo "== $name: ${cmd[*]}"
  "${cmd[@]}" 2>&1 | tee "$tmp/log.txt"
  echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$tmp/machine.txt"
  mv "$tmp" "$out"
}

for file in $DATASETS; do
  path="$DATA_DIR/$file"
  [ -f "$path" ] || { echo "isam2.sh: $path not found (HAMAL_DATA_DIR)" >&2; exit 1; }
  poses=$(grep -c -E '^(VERTEX_SE2|VERTEX2) ' "$path" || true)
  run "${file%%.*}" "${poses:-0}" --data "$path"
done
for n in $SIZES; do
  run "gen$n" "$n" --generate "$n" --seed 1
done

"$PY" plugins/gtsam/side_by_side.py "$RESULTS"
