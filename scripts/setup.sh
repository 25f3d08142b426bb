#!/usr/bin/env bash
# Installs hamal's build dependencies from Debian 12 packages (nothing is
# downloaded from anywhere else) and configures + builds the project in
# ./build (Release). Idempotent: packages already installed are not fetched
# again and an existing build directory is reused. zlib1g-dev reads gzip
# CARMEN logs (apps/carmen). python3-matplotlib draws
# the figures of scripts/report.sh (and its test in tests/sweep); clang-14
# and libclang-rt-14-dev (libFuzzer) build the fuzz targets of tests/fuzz.
set -euo pipefail
cd "$(dirname "$0")/.."

# python3-scipy: apps/moss/moss_report.py's paired tests (Wilcoxon signed-rank).
PACKAGES=(build-essential cmake libceres-dev libeigen3-dev libsuitesparse-dev
          libgflags-dev libgoogle-glog-dev libgtest-dev nlohmann-json3-dev
          python3 python3-matplotlib python3-scipy pkg-config libigraph-dev libnanoflann-dev
          libboost-dev clang-14 libclang-rt-14-dev zlib1g-dev)

# The Python module of python/: built with pybind11 and Python's headers,
# used with numpy, tested with pytest; its stubs made by mypy's stubgen;
# `pip install .` (setup.py) into a venv with Debian's setuptools and wheel.
PACKAGES+=(python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-mypy
           python3-venv python3-setuptools python3-wheel)

# A single-node Slurm for the test of the sweep's Slurm executor
# (scripts/local_slurm.sh starts it as plain processes; no service is enabled).
PACKAGES+=(slurmctld slurmd slurm-client munge)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" > build.configure.log 2>&1 \
  || { cat build.configure.log; exit 1; }
cmake --build build -j "$(nproc)"
