#!/usr/bin/env bash
# Builds the libFuzzer targets in build-fuzz (clang, with AddressSanitizer
# and UndefinedBehaviorSanitizer) and runs each for a fixed time from its
# seed corpus in tests/fuzz/corpus/ (README.md here: how to run longer).
#
#   tests/fuzz/run.sh [seconds per target, default 30]
#
# Inputs the fuzzer finds interesting go to a scratch corpus in build-fuzz,
# not into the repository's seeds; a crash leaves its input in
# build-fuzz/artifacts/ and makes this script fail. Without clang and
# libFuzzer it says so and exits 0 (the GoogleTest suites still run).
# The fuzzer's random seed is HAMAL_FUZZ_SEED (1), so that CI explores the
# same inputs first on every run; set another seed to look elsewhere.
# HAMAL_FUZZ_TARGETS (all six) picks targets by name, e.g. "world_file carmen_log".
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-30}"

cxx=""
for c in clang++-14 clang++; do
  if command -v "$c" >/dev/null 2>&1; then cxx="$c"; break; fi
done
probe="$(mktemp -d)"
trap 'rm -rf "$probe"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' \
  > "$probe/probe.cc"
if [ -z "$cxx" ] || ! "$cxx" -fsanitize=fuzzer "$probe/probe.cc" -o "$probe/probe" 2>/dev/null; then
  echo "fuzz: clang with libFuzzer not found (Debian: clang-14 libclang-rt-14-dev); skipped"
  exit 0
fi

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
flags="-O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
mkdir -p build-fuzz
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_COMPILER="$cxx" "${launcher[@]}" \
      -DHAMAL_BUILD_TESTS=OFF -DHAMAL_BUILD_FUZZERS=ON "-DCMAKE_CXX_FLAGS=$flags" \
      "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined" \
      "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" > build-fuzz/configure.log 2>&1 \
  || { cat build-fuzz/configure.log; exit 1; }
cmake --build build-fuzz -j "$(nproc)" --target graph_reader_fuzz step_path_fuzz world_file_fuzz \
  results_folder_fuzz carmen_log_fuzz false_edge_list_fuzz

export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
mkdir -p build-fuzz/artifacts
for target in ${HAMAL_FUZZ_TARGETS:-graph_reader step_path world_file results_folder carmen_log false_edge_list}; do
  scratch="build-fuzz/corpus/$target"
  mkdir -p "$scratch"
  echo "fuzz: $target for $seconds s"
  build-fuzz/fuzz/${target}_fuzz -max_total_time="$seconds" -seed="${HAMAL_FUZZ_SEED:-1}" -timeout=20 -rss_limit_mb=2048 \
    -max_len=4096 -print_final_stats=1 -artifact_prefix=build-fuzz/artifacts/${target}- \
    "$scratch" "tests/fuzz/corpus/$target" 2>&1 | grep -v '^#[0-9]*.*\(NEW\|REDUCE\|pulse\)' || {
      echo "fuzz: $target failed; its input is in build-fuzz/artifacts/"; exit 1; }
done
