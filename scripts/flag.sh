#!/usr/bin/env bash
# FLAG's experiments (thesis sec. 4.4), one command each:
#   scripts/flag.sh dynamic|static|landmarks|office|victoria|carmen [--trials N] [--jobs N] [-- hamal_flag flags]
# Builds hamal_flag if needed, then runs apps/flag/flag_experiments.py at
# nice 10 (trials in parallel on every core, resumable); results in
# results/flag/<experiment>/ (trials.csv, table.md, the figure).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x build/apps/hamal_flag ]; then
  [ -d build ] || cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
  nice -n 10 cmake --build build -j "$(nproc)" --target hamal_flag
fi
# Debian's python3 has python3-matplotlib; a python3 earlier on PATH may not.
PY=python3
[ -x /usr/bin/python3 ] && PY=/usr/bin/python3
exec nice -n 10 "$PY" apps/flag/flag_experiments.py "$@"
