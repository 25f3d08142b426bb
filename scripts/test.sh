#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh) and runs the whole GoogleTest suite
# with ctest. The public datasets are read from ../shared/data (override with
# HAMAL_DATA_DIR); tests that need a missing file are skipped and say so.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cd build
ctest -j "$(nproc)" --output-on-failure --timeout 900
