#!/usr/bin/env bash
# The cost target of the robust benchmark (apps/robust/FIGURES.md):
# incremental GNC on M3500 + 1000 random false loop closures, seeds 1-5,
# against plain least squares on the clean file with the same back-end. The
# runs are interleaved in one invocation (clean, then each seed, REPEATS
# times), so a machine that is busier for a while slows both sides; it
# prints the median time of each, their ratio and the step p99 (median over
# the repeats).
#
#   scripts/robust_cost.sh [WORKDIR] [SPEC] [REPEATS]
#   scripts/robust_cost.sh results/cost aprilsam:robust=gnc,gnc_threshold=1.5 3
#
# WORKDIR (default results/robust_cost) gets the spoiled files (hamal_spoil,
# the benchmark's spoiling) and every run's summary and rows. SPEC defaults
# to aprilsam at M3500's stated threshold; its back-end with robust=none is
# the clean run. HAMAL_BUILD=DIR uses DIR/apps's executables; HAMAL_DATA_DIR
# the datasets (default ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
WORK="${1:-results/robust_cost}"
SPEC="${2:-aprilsam:robust=gnc,gnc_threshold=1.5}"
REPEATS="${3:-3}"
DATA="${HAMAL_DATA_DIR:-../shared/data}"
if [ -n "${HAMAL_BUILD:-}" ]; then
  BIN="$HAMAL_BUILD/apps"
else
  [ -f build/CMakeCache.txt ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build build -j2 --target hamal_spoil hamal_robust > /dev/null
  BIN=build/apps
fi
CLEAN="${SPEC%%:*}:robust=none"
mkdir -p "$WORK"
spoil() {  # N SEED NAME
  [ -f "$WORK/$3.g2o" ] || "$BIN/hamal_spoil" --data "$DATA/M3500.toro" --outliers "$1" \
    --policy random --seed "$2" --output "$WORK/$3.g2o" > /dev/null
}
spoil 0 1 clean
for s in 1 2 3 4 5; do spoil 1000 "$s" "random-1000-s$s"; done
run() {  # FILE SPEC TAG
  "$BIN/hamal_robust" --data "$WORK/$1.g2o" --backend "$2" --summary "$WORK/$3.json" \
    --rows "$WORK/$3.csv" > "$WORK/$3.log" 2>&1
}
for r in $(seq 1 "$REPEATS"); do
  echo "robust_cost: repeat $r of $REPEATS" >&2
  run clean "$CLEAN" "clean-$r"
  for s in 1 2 3 4 5; do run "random-1000-s$s" "$SPEC" "s$s-$r"; done
done
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
"$PY" - "$WORK" "$REPEATS" "$SPEC" "$CLEAN" <<'EOF'
import json, statistics, sys
sys.path.insert(0, "apps/robust")
from hamal_robust_report import step_p99  # the report's p99, so both agree
work, repeats, spec, clean_spec = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
def seconds(tag):
    return json.load(open(f"{work}/{tag}.json"))["seconds"]
def p99(tag):
    return step_p99(f"{work}/{tag}.csv")
reps = range(1, repeats + 1)
clean = statistics.median(seconds(f"clean-{r}") for r in reps)
print(f"{clean_spec} on clean M3500: median {clean:.3f} s of {repeats}")
print("| seed | time s | x clean | step p99 ms | ATE m | true rejected | false accepted |")
print("|---|---|---|---|---|---|---|")
for s in range(1, 6):
    t = statistics.median(seconds(f"s{s}-{r}") for r in reps)
    p = statistics.median(p99(f"s{s}-{r}") for r in reps)
    j = json.load(open(f"{work}/s{s}-1.json"))
    print(f"| {s} | {t:.3f} | {t / clean:.2f} | {p * 1e3:.1f} | {j['ate_translation']:.3g} | "
          f"{j['true_switched_off']} | {j['false_accepted']} |")
EOF
