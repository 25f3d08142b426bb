#!/usr/bin/env bash
# The Slurm executor's overhead (apps/sweep/README.md): the same sweep of 20
# runs, 2 at a time, twice with the local executor (--jobs 2) and twice through
# a single-node Slurm started here by scripts/local_slurm.sh (--executor slurm
# --max_parallel 2), each into a fresh results folder; prints the wall times
# and the ratio of their sums. A benchmark, not a test: the figure depends on the load of
# the machine.
#
#   scripts/slurm_overhead.sh [DATASET]   default: ../shared/data/M3500.toro
#                                         (a generated 2000-pose world if absent)
#
# The 20 runs are AprilSAM over 20 delta_T values, no chi2 rows and no
# reference solve, so each is a short bench process and the scheduler's
# share shows. Environment: HAMAL_BUILD=DIR (default ./build, built if absent).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${HAMAL_BUILD:-build}"
[ -x "$BUILD/apps/hamal_bench" ] || cmake --build "$BUILD" -j2 --target hamal_bench
BENCH="$(cd "$BUILD/apps" && pwd)/hamal_bench"
DATA="${1:-../shared/data/M3500.toro}"

work=$(mktemp -d /tmp/hamal_slurm_overhead.XXXXXX)
trap 'scripts/local_slurm.sh stop "$work/cluster" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
if [ -f "$DATA" ]; then
  dataset="{\"data\": \"$(cd "$(dirname "$DATA")" && pwd)/$(basename "$DATA")\"}"
else
  echo "slurm_overhead: $DATA not found, using a generated 2000-pose world" >&2
  dataset='{"generate": 2000, "seed": 1}'
fi
values=$(python3 -c 'print(",".join(str(round(0.001 * 1.4 ** i, 6)) for i in range(20)))')
cat > "$work/spec.json" <<EOF
{"datasets": {"d": $dataset},
 "groups": [{"name": "delta_t", "backends": ["aprilsam"], "chi2_every": 0,
             "reference": "none", "grid": {"delta_t": [$values]}}]}
EOF

scripts/local_slurm.sh start "$work/cluster" > /dev/null
export SLURM_CONF="$work/cluster/slurm.conf"

seconds() {
  local t0 t1
  t0=$(date +%s.%N)
  python3 apps/sweep/hamal_sweep.py "$work/spec.json" --bench "$BENCH" --quiet "$@" >&2
  t1=$(date +%s.%N)
  python3 -c "print(f'{$t1 - $t0:.1f}')"
}
# ABBA order, so that a change in the machine's load between the two falls
# on both alike.
local_s=$(seconds --results "$work/local1" --jobs 2)
slurm_s=$(seconds --results "$work/slurm1" --executor slurm --max_parallel 2 --poll 0.5)
slurm2_s=$(seconds --results "$work/slurm2" --executor slurm --max_parallel 2 --poll 0.5)
local2_s=$(seconds --results "$work/local2" --jobs 2)
runs=$(find "$work/slurm1/d" "$work/slurm2/d" -mindepth 1 -maxdepth 1 -not -name '.*' | wc -l)
echo "20 runs, 2 at a time (ABBA): local ${local_s} + ${local2_s} s," \
     "Slurm ${slurm_s} + ${slurm2_s} s ($runs of 40 runs written through Slurm)," \
     "ratio $(python3 -c "print(f'{($slurm_s + $slurm2_s) / ($local_s + $local2_s):.2f}')")x"
