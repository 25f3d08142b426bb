#!/usr/bin/env bash
# The main job on an embedded default that needs no download: generate a
# synthetic Manhattan world, solve it with every registered back-end under
# the thesis protocol, and print the comparison table.
# Extra arguments go to hamal_bench (e.g. --generate 3500 or --data FILE).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/apps/hamal_bench --backend all "$@"
