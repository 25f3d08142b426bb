#!/usr/bin/env bash
# docs/BENCHMARKS.md regenerated: builds hamal (scripts/setup.sh), runs
# hamal_bench under the thesis protocol on each public dataset found in
# ../shared/data (the AprilSAM variants, medians of 3 runs, the batch optimum
# of cholesky as reference) into docs/benchmarks/ (committed beside the document), and writes the document
# from the JSON summaries with the date, machine and commit of each run
# (apps/report/hamal_benchmarks.py). Datasets already measured there are not
# run again; delete docs/benchmarks/ to measure afresh.
#
#   scripts/benchmarks.sh [hamal_benchmarks.py options]
#   scripts/benchmarks.sh --write_only          # redraw the document only
#   scripts/benchmarks.sh --datasets M3500.toro --backend "aprilsam;cholesky"
#
# Environment: HAMAL_BUILD=DIR uses DIR/apps/hamal_bench instead of building
# ./build; HAMAL_DATA_DIR=DIR reads the datasets from DIR. The runs take
# minutes of CPU (city10000 most of it) and run under nice -n 10.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench_environment.sh
exec nice -n 10 "$PY" apps/report/hamal_benchmarks.py --bench "$BENCH" "$@"
