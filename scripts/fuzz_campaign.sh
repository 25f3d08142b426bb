#!/usr/bin/env bash
# The libFuzzer targets of tests/fuzz as a benchmark, not CI: each for ten
# minutes (CI gives them 30 s), one at a time and at the lowest priority so
# a shared machine keeps its other work. The figures (executions, coverage,
# corpus size) are libFuzzer's final stats per target; a crash stops the
# campaign with its input in build-fuzz/artifacts/ (tests/fuzz/README.md).
#
#   scripts/fuzz_campaign.sh [seconds per target, default 600] [target ...]
#
# Targets default to all of them (graph_reader step_path world_file
# results_folder carmen_log false_edge_list); HAMAL_FUZZ_SEED picks the
# fuzzer's seed (1).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
shift || true
targets="${*:-graph_reader step_path world_file results_folder carmen_log false_edge_list}"
HAMAL_FUZZ_TARGETS="$targets" exec nice -n 19 tests/fuzz/run.sh "$seconds"
