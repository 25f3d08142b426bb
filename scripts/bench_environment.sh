# Sourced by the scripts that drive hamal_bench (benchmarks.sh, report.sh,
# scale.sh) from the repository's root: PY, Debian's python3 when it is
# there (the one the hamal module and python3-matplotlib are for), and BENCH,
# $HAMAL_BUILD/apps/hamal_bench, or ./build's after scripts/setup.sh.
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
if [ -n "${HAMAL_BUILD:-}" ]; then
  BENCH="$HAMAL_BUILD/apps/hamal_bench"
else
  scripts/setup.sh
  BENCH=build/apps/hamal_bench
fi
